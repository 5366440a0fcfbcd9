#include "jobs/slurm.h"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <iostream>
#include <sstream>
#include <thread>

#include "core/error.h"
#include "core/io.h"
#include "scenes/dataset.h"
#include "design/study.h"
#include "study/tolerance.h"

extern char** environ;

namespace hovs::jobs {
namespace fs = std::filesystem;

namespace {

// The commands whose runs can be split into shards and merged (their --shard I/N and hovs merge).
const std::vector<std::string>& ShardableCommands() {
  static const std::vector<std::string> names = {"dataset", "tolerance", "design"};
  return names;
}

std::string Quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string LastLine(const fs::path& log) {
  if (!fs::is_regular_file(log)) return "(no log)";
  std::istringstream in(ReadFile(log));
  std::string line, last = "(empty log)";
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  return last;
}

// Array indices of scontrol's ArrayTaskId: "3", "2-7", "1,3-5", each possibly followed by "%K".
std::vector<int> ParseIndices(std::string text) {
  std::vector<int> out;
  text = text.substr(0, text.find('%'));
  std::stringstream ss(text);
  std::string part;
  while (std::getline(ss, part, ',')) {
    int a = 0, b = 0;
    if (std::sscanf(part.c_str(), "%d-%d", &a, &b) == 2) {
      for (int i = a; i <= b; ++i) out.push_back(i);
    } else if (std::sscanf(part.c_str(), "%d", &a) == 1) {
      out.push_back(a);
    }
  }
  return out;
}

std::map<std::string, std::string> Fields(const std::string& line) {
  std::map<std::string, std::string> f;
  std::istringstream in(line);
  std::string word;
  while (in >> word) {
    const size_t eq = word.find('=');
    if (eq != std::string::npos) f[word.substr(0, eq)] = word.substr(eq + 1);
  }
  return f;
}

}  // namespace

void SlurmOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(shards >= 1 && shards <= 100000, where, "--shards must be 1..100000");
  HOVS_REQUIRE(cpus >= 0 && cpus <= 4096, where, "--cpus must be 0..4096");
  HOVS_REQUIRE(array_throttle >= 0, where, "--array-throttle must be >= 0");
  for (const std::string* s : {&partition, &time, &mem, &job_name})
    HOVS_REQUIRE(s->find_first_of(" \t\n'\"\\$`") == std::string::npos, where, "'", *s,
                 "' holds a space or a shell character");
}

ShardedCommand ParseShardedCommand(const std::vector<std::string>& line) {
  const std::string where = "hovs slurm submit";
  HOVS_REQUIRE(!line.empty(), where, "give the hovs command to run after --, e.g. -- dataset --kind ... --out D");
  ShardedCommand c;
  c.name = line[0];
  std::string known;
  for (const auto& n : ShardableCommands()) known += (known.empty() ? "" : ", ") + n;
  HOVS_REQUIRE(std::find(ShardableCommands().begin(), ShardableCommands().end(), c.name) != ShardableCommands().end(),
               where, "'", c.name, "' cannot be sharded (shardable: ", known, ")");
  for (size_t i = 0; i < line.size(); ++i) {
    const std::string& a = line[i];
    HOVS_REQUIRE(a.rfind("--shard", 0) != 0, where, "the command has a --shard of its own; the job sets it per task");
    if (a == "--out" || a == "-o") {
      HOVS_REQUIRE(i + 1 < line.size(), where, a, " needs a folder");
      c.out = line[++i];
    } else if (a.rfind("--out=", 0) == 0) {
      c.out = a.substr(6);
    } else {
      c.args.push_back(a);
    }
  }
  HOVS_REQUIRE(!c.out.empty(), where, "the command needs --out (the merged result's folder)");
  c.out = fs::absolute(c.out).lexically_normal();
  return c;
}

fs::path ShardDir(const fs::path& job_dir, int index) {
  return job_dir / "shards" / ("shard-" + std::to_string(index));
}

std::string SbatchScript(const ShardedCommand& command, const SlurmOptions& o, const fs::path& binary,
                         const fs::path& job_dir) {
  o.Check("slurm options");
  std::ostringstream s;
  s << "#!/bin/bash\n# hovs " << command.name << " as a Slurm array of " << o.shards
    << " shards (written by hovs slurm submit; submit it again with: sbatch " << (job_dir / "job.sbatch").string()
    << ").\n# Task I writes shard I of " << o.shards << " into shards/shard-I; hovs merge joins them into "
    << command.out.string() << ".\n";
  s << "#SBATCH --job-name=" << o.job_name << "-" << command.name << "\n";
  s << "#SBATCH --array=0-" << o.shards - 1;
  if (o.array_throttle > 0) s << "%" << o.array_throttle;
  s << "\n#SBATCH --output=" << (job_dir / "logs" / "task-%a.out").string() << "\n";
  s << "#SBATCH --chdir=" << fs::current_path().string() << "\n";
  if (!o.partition.empty()) s << "#SBATCH --partition=" << o.partition << "\n";
  if (!o.time.empty()) s << "#SBATCH --time=" << o.time << "\n";
  if (!o.mem.empty()) s << "#SBATCH --mem=" << o.mem << "\n";
  if (o.cpus > 0) s << "#SBATCH --cpus-per-task=" << o.cpus << "\n";
  s << "set -eu\nexec " << Quote(binary.string());
  for (const auto& a : command.args) s << " " << Quote(a);
  // A task Slurm requeues (preemption, a node lost) continues its shard where the killed attempt stopped.
  if (command.name == "dataset") s << " --resume";
  s << " --shard \"${SLURM_ARRAY_TASK_ID}/" << o.shards << "\" --out "
    << Quote((job_dir / "shards").string() + "/shard-") << "\"${SLURM_ARRAY_TASK_ID}\"\n";
  return s.str();
}

ProgramRun RunProgram(const std::vector<std::string>& argv) {
  HOVS_REQUIRE(!argv.empty(), "run program", "no program given");
  int fds[2];
  HOVS_REQUIRE(pipe(fds) == 0, argv[0], "cannot create a pipe");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 2);
  posix_spawn_file_actions_addclose(&actions, fds[0]);
  posix_spawn_file_actions_addclose(&actions, fds[1]);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, argv[0].c_str(), &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(fds[1]);
  ProgramRun r;
  if (rc != 0) {
    close(fds[0]);
    r.exit_code = 127;
    r.output = argv[0] + ": cannot be started (" + std::strerror(rc) + ")";
    return r;
  }
  char buf[4096];
  ssize_t n;
  while ((n = read(fds[0], buf, sizeof buf)) > 0 || (n < 0 && errno == EINTR))
    if (n > 0) r.output.append(buf, static_cast<size_t>(n));
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {}
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  return r;
}

std::string SubmitScript(const fs::path& script, bool hold) {
  std::vector<std::string> argv = {"sbatch", "--parsable"};
  if (hold) argv.push_back("--hold");
  argv.push_back(script.string());
  const ProgramRun r = RunProgram(argv);
  HOVS_REQUIRE(r.exit_code != 127, "sbatch", "not found on PATH: is Slurm's client installed (Debian: slurm-client)?");
  HOVS_REQUIRE(r.exit_code == 0, "sbatch", "refused ", script.string(), ": ", r.output);
  std::string id = r.output.substr(0, r.output.find_first_of(";\n"));  // "id" or "id;cluster"
  HOVS_REQUIRE(!id.empty() && id.find_first_not_of("0123456789") == std::string::npos, "sbatch", "unexpected reply '",
               r.output, "' (expected a job id)");
  return id;
}

void ReleaseJob(const std::string& job_id) {
  const ProgramRun r = RunProgram({"scontrol", "release", job_id});
  HOVS_REQUIRE(r.exit_code == 0, "scontrol release " + job_id, "refused: ", r.output);
}

void CancelJob(const std::string& job_id) {
  const ProgramRun r = RunProgram({"scancel", job_id});
  HOVS_REQUIRE(r.exit_code == 0, "scancel " + job_id, "refused: ", r.output);
}

bool TaskState::Active() const {
  for (const char* s : {"PENDING", "RUNNING", "CONFIGURING", "COMPLETING", "REQUEUED", "RESIZING", "SUSPENDED",
                        "STAGE_OUT", "REQUEUE_HOLD", "REQUEUE_FED"})
    if (state == s) return true;
  return false;
}

std::vector<TaskState> QueryTasks(const std::string& job_id, int shards, const fs::path& job_dir) {
  std::vector<TaskState> tasks(static_cast<size_t>(shards));
  for (int i = 0; i < shards; ++i) {
    tasks[i].index = i;
    tasks[i].log = job_dir / "logs" / ("task-" + std::to_string(i) + ".out");
  }
  const ProgramRun r = RunProgram({"scontrol", "show", "job", "-o", job_id});
  HOVS_REQUIRE(r.exit_code != 127, "scontrol", "not found on PATH: is Slurm's client installed?");
  // An unknown job (Slurm forgets finished jobs after MinJobAge) leaves every task UNKNOWN: the outputs decide.
  if (r.exit_code == 0) {
    std::istringstream in(r.output);
    std::string line;
    while (std::getline(in, line)) {
      const auto f = Fields(line);
      if (!f.count("ArrayTaskId") || !f.count("JobState")) continue;
      for (int i : ParseIndices(f.at("ArrayTaskId"))) {
        if (i < 0 || i >= shards) continue;
        tasks[i].state = f.at("JobState");
        tasks[i].exit_code = f.count("ExitCode") ? f.at("ExitCode") : "";
      }
    }
  }
  for (auto& t : tasks) t.output_complete = fs::exists(ShardDir(job_dir, t.index) / kOutputMarker);
  return tasks;
}

std::vector<TaskState> WaitForJob(const std::string& job_id, int shards, const fs::path& job_dir, double poll_s,
                                  double timeout_s) {
  const auto start = std::chrono::steady_clock::now();
  for (;;) {
    auto tasks = QueryTasks(job_id, shards, job_dir);
    int active = 0;
    for (const auto& t : tasks) active += t.Active();
    if (active == 0) {
      for (const auto& t : tasks)
        HOVS_REQUIRE(t.output_complete, "slurm job " + job_id, "shard ", t.index, " failed (state ", t.state,
                     t.exit_code.empty() ? "" : ", exit " + t.exit_code, "; log ", t.log.string(), ": ",
                     LastLine(t.log), ")");
      return tasks;
    }
    const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    HOVS_REQUIRE(timeout_s <= 0 || waited < timeout_s, "slurm job " + job_id, active, " of ", shards,
                 " tasks still pending or running after ", timeout_s, " s (hovs slurm status ", job_dir.string(), ")");
    std::this_thread::sleep_for(std::chrono::duration<double>(poll_s));
  }
}

nlohmann::json TasksJson(const std::vector<TaskState>& tasks) {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& t : tasks)
    j.push_back({{"shard", t.index},
                 {"state", t.state},
                 {"exit_code", t.exit_code},
                 {"output_complete", t.output_complete},
                 {"log", t.log.string()}});
  return j;
}

void MergeShards(const ShardedCommand& command, int shards, const fs::path& job_dir) {
  std::vector<fs::path> dirs;
  for (int i = 0; i < shards; ++i) dirs.push_back(ShardDir(job_dir, i));
  if (command.name == "tolerance")
    for (const auto& w : study::MergeToleranceShards(dirs, command.out))
      std::cerr << "hovs slurm: warning: " << w << "\n";
  else if (command.name == "design")
    design::MergeDesignShards(dirs, command.out);
  else if (command.name == "dataset")
    scenes::MergeDatasetShards(dirs, command.out);
  else
    throw Error("hovs slurm", "no merge for '" + command.name + "'");
}

}  // namespace hovs::jobs
