// hovs slurm: a sharded hovs command as a Slurm array job (jobs/slurm.h). `submit` writes the job folder and its
// sbatch script, submits it, and with --wait follows the tasks and merges the shards; `status` reports a job
// folder's tasks.
#include <unistd.h>

#include <cstdio>
#include <iostream>

#include "apps/commands.h"
#include "core/error.h"
#include "core/io.h"
#include "core/json.h"
#include "jobs/slurm.h"

namespace hovs::apps {
namespace {
namespace fs = std::filesystem;

struct SubmitOptions {
  std::vector<std::string> command;
  jobs::SlurmOptions slurm;
  std::string job_dir;
  bool wait = false;
  double poll = 5, timeout = 0;
};

fs::path SelfBinary() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  HOVS_REQUIRE(!ec, "hovs slurm", "cannot find the hovs executable (/proc/self/exe)");
  return p;
}

void PrintTasks(const std::vector<jobs::TaskState>& tasks) {
  int complete = 0;
  for (const auto& t : tasks) {
    complete += t.output_complete;
    std::printf("  shard %d: %s%s%s\n", t.index, t.state.c_str(),
                t.exit_code.empty() ? "" : (" exit " + t.exit_code).c_str(),
                t.output_complete ? ", output complete" : "");
  }
  std::printf("  %d of %zu shards complete\n", complete, tasks.size());
}

int RunSubmit(const SubmitOptions& o, const GlobalOptions& global) {
  o.slurm.Check("hovs slurm submit");
  HOVS_REQUIRE(o.poll > 0, "--poll", "must be positive");
  const jobs::ShardedCommand command = jobs::ParseShardedCommand(o.command);
  const fs::path job_dir =
      fs::absolute(o.job_dir.empty() ? command.out.string() + ".slurm" : o.job_dir).lexically_normal();
  CheckOutputFolder(command.out, "merge", {});
  // The job folder is built aside and submitted held: only once Slurm has taken the job does the folder replace
  // an earlier submission's (whose shards stay untouched by a refused one), and the tasks are released when their
  // folders are in place. A refused submission leaves nothing behind.
  StagedDirectory stage(job_dir, "slurm submit");
  fs::create_directories(stage.staging() / "shards");
  fs::create_directories(stage.staging() / "logs");
  const fs::path script = job_dir / "job.sbatch", staged_script = stage.staging() / "job.sbatch";
  WriteFileAtomic(staged_script, jobs::SbatchScript(command, o.slurm, SelfBinary(), job_dir));
  fs::permissions(staged_script, fs::perms::owner_exec, fs::perm_options::add);
  const std::string id = jobs::SubmitScript(staged_script, /*hold=*/true);
  nlohmann::json record = {{"tool", "hovs slurm submit"},
                           {"versions", Versions()},
                           {"job_id", id},
                           {"command", o.command},
                           {"shards", o.slurm.shards},
                           {"out", command.out.string()},
                           {"script", script.string()},
                           {"binary", SelfBinary().string()},
                           {"slurm",
                            {{"partition", o.slurm.partition},
                             {"time", o.slurm.time},
                             {"mem", o.slurm.mem},
                             {"cpus", o.slurm.cpus},
                             {"array_throttle", o.slurm.array_throttle}}}};
  try {
    WriteFileAtomic(stage.staging() / "submission.json", record.dump(1) + "\n");
    stage.Commit();
  } catch (...) {
    jobs::CancelJob(id);
    throw;
  }
  jobs::ReleaseJob(id);
  if (!global.quiet)
    std::printf("hovs slurm submit: job %s, %d shards of hovs %s (%s)\n", id.c_str(), o.slurm.shards,
                command.name.c_str(), script.c_str());
  if (!o.wait) return 0;
  const auto tasks = jobs::WaitForJob(id, o.slurm.shards, job_dir, o.poll, o.timeout);
  jobs::MergeShards(command, o.slurm.shards, job_dir);
  record["tasks"] = jobs::TasksJson(tasks);
  record["merged"] = command.out.string();
  WriteFileAtomic(job_dir / "submission.json", record.dump(1) + "\n");
  if (global.json) {
    std::cout << record.dump(1) << "\n";
  } else if (!global.quiet) {
    PrintTasks(tasks);
    std::printf("hovs slurm submit: merged %d shards -> %s\n", o.slurm.shards, command.out.c_str());
  }
  return 0;
}

int RunStatus(const std::string& dir, const GlobalOptions& global) {
  const fs::path job_dir = fs::absolute(dir);
  const nlohmann::json record = ReadJsonFile(job_dir / "submission.json");
  HOVS_REQUIRE(record.contains("job_id") && record["job_id"].is_string() && record.contains("shards") &&
                   record["shards"].is_number_integer() && record["shards"].get<int>() >= 1,
               (job_dir / "submission.json").string(), "not a hovs slurm submission record");
  const std::string id = record["job_id"];
  const auto tasks = jobs::QueryTasks(id, record["shards"].get<int>(), job_dir);
  if (global.json) {
    std::cout << nlohmann::json{{"job_id", id}, {"tasks", jobs::TasksJson(tasks)}}.dump(1) << "\n";
  } else if (!global.quiet) {
    std::printf("hovs slurm status: job %s (%s)\n", id.c_str(), job_dir.c_str());
    PrintTasks(tasks);
  }
  return 0;
}

}  // namespace

Runner SetupSlurm(CLI::App* sub, const GlobalOptions* global) {
  sub->require_subcommand(1, 1);
  auto o = std::make_shared<SubmitOptions>();
  auto status_dir = std::make_shared<std::string>();
  CLI::App* submit =
      sub->add_subcommand("submit",
                          "Run a hovs command as a Slurm array of shards: hovs slurm submit [options] -- "
                          "dataset ... --out D");
  submit->add_option("COMMAND", o->command, "the hovs command line, after --")->required();
  AddBounded(submit, "--shards", &o->slurm.shards, "array tasks, one shard each", 1, 100000);
  submit->add_option("--partition", o->slurm.partition, "Slurm partition (default: the cluster's)");
  submit->add_option("--time", o->slurm.time, "time limit per task, as sbatch takes it (e.g. 2:00:00)");
  submit->add_option("--mem", o->slurm.mem, "memory per task, as sbatch takes it (e.g. 8G)");
  AddBounded(submit, "--cpus", &o->slurm.cpus, "CPUs per task (0: the cluster's default)", 0, 4096);
  AddBounded(submit, "--array-throttle", &o->slurm.array_throttle, "tasks running at once at most (0: no limit)", 0,
             100000);
  submit->add_option("--job-dir", o->job_dir, "the job folder (default: the command's --out + .slurm)");
  submit->add_flag("--wait", o->wait, "wait for the tasks, then merge the shards into the command's --out");
  AddBounded(submit, "--poll", &o->poll, "seconds between queries while waiting", 0, 3600, true);
  AddBounded(submit, "--timeout", &o->timeout, "give up waiting after this many seconds (0: never)", 0, 1e7);
  CLI::App* status =
      sub->add_subcommand("status", "The tasks of a job folder (hovs slurm submit): states, shards done");
  status->add_option("JOB_DIR", *status_dir, "the job folder")->required();
  return [=]() {
    if (submit->parsed()) return RunSubmit(*o, *global);
    return RunStatus(*status_dir, *global);
  };
}

}  // namespace hovs::apps
