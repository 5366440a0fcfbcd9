// The Slurm job layer without a cluster: the command split for sharding, the array script, the program runner,
// and the tasks' states parsed from scontrol's one-line records (a stand-in scontrol on PATH prints them).
#include "jobs/slurm.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <fstream>

#include "core/error.h"
#include "core/io.h"
#include "tests/cli_helper.h"

namespace hovs {
namespace {
namespace fs = std::filesystem;

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) { return e.what(); }
  return "";
}

TEST(Slurm, ACommandIsSplitIntoItsArgumentsAndItsOutput) {
  const auto c = jobs::ParseShardedCommand({"dataset", "--scene", "s.yaml", "-n", "8", "--out", "/data/set"});
  EXPECT_EQ(c.name, "dataset");
  EXPECT_EQ(c.args, (std::vector<std::string>{"dataset", "--scene", "s.yaml", "-n", "8"}));
  EXPECT_EQ(c.out, fs::path("/data/set"));
  EXPECT_EQ(jobs::ParseShardedCommand({"dataset", "--out=/x/y"}).out, fs::path("/x/y"));
  EXPECT_NE(ErrorOf([] {
              jobs::ParseShardedCommand({"calibrate", "--out", "d"});
            }).find("cannot be sharded"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { jobs::ParseShardedCommand({"dataset", "-n", "3"}); }).find("needs --out"), std::string::npos);
  EXPECT_NE(ErrorOf([] {
              jobs::ParseShardedCommand({"dataset", "--shard", "0/2", "--out", "d"});
            }).find("--shard"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { jobs::ParseShardedCommand({}); }).find("give the hovs command"), std::string::npos);
}

TEST(Slurm, TheArrayScriptRunsOneShardPerTaskWithItsArgumentsQuoted) {
  const auto c = jobs::ParseShardedCommand({"dataset", "--scene", "my scene's.yaml", "--out", "/d/set"});
  jobs::SlurmOptions o;
  o.shards = 5, o.array_throttle = 2, o.partition = "gpu", o.time = "1:00:00", o.mem = "8G", o.cpus = 4;
  const std::string s = jobs::SbatchScript(c, o, "/opt/hovs/bin/hovs", "/d/set.slurm");
  for (const char* line :
       {"#SBATCH --array=0-4%2\n", "#SBATCH --output=/d/set.slurm/logs/task-%a.out\n", "#SBATCH --partition=gpu\n",
        "#SBATCH --time=1:00:00\n", "#SBATCH --mem=8G\n", "#SBATCH --cpus-per-task=4\n",
        "exec '/opt/hovs/bin/hovs' 'dataset' '--scene' 'my scene'\\''s.yaml' --resume --shard "
        "\"${SLURM_ARRAY_TASK_ID}/5\" --out '/d/set.slurm/shards/shard-'\"${SLURM_ARRAY_TASK_ID}\"\n"})
    EXPECT_NE(s.find(line), std::string::npos) << line << "\nnot in\n" << s;
  o.partition = "a b";
  EXPECT_NE(ErrorOf([&] { jobs::SbatchScript(c, o, "/h", "/j"); }).find("shell character"), std::string::npos);
}

TEST(Slurm, ProgramsRunWithTheirExitCodeAndOutput) {
  const auto ok = jobs::RunProgram({"sh", "-c", "echo out; echo err >&2; exit 3"});
  EXPECT_EQ(ok.exit_code, 3);
  EXPECT_NE(ok.output.find("out"), std::string::npos);
  EXPECT_NE(ok.output.find("err"), std::string::npos);
  EXPECT_EQ(jobs::RunProgram({"/nonexistent/program"}).exit_code, 127);
}

TEST(Slurm, TaskStatesComeFromScontrolAndTheShardFolders) {
  const fs::path dir = test::Scratch("jobs", "states");
  fs::create_directories(dir / "bin");
  // scontrol's records of an array job: two tasks done or failed, the rest pending in one collapsed record.
  WriteFileAtomic(dir / "bin" / "scontrol",
                  "#!/bin/sh\n"
                  "echo 'JobId=11 ArrayJobId=10 ArrayTaskId=0 JobState=COMPLETED Reason=None ExitCode=0:0'\n"
                  "echo 'JobId=12 ArrayJobId=10 ArrayTaskId=1 JobState=FAILED Reason=NonZeroExitCode ExitCode=2:0'\n"
                  "echo 'JobId=10 ArrayJobId=10 ArrayTaskId=2-3,5%2 JobState=PENDING Reason=JobArrayTaskLimit'\n");
  fs::permissions(dir / "bin" / "scontrol", fs::perms::owner_all);
  fs::create_directories(jobs::ShardDir(dir, 0));
  WriteFileAtomic(jobs::ShardDir(dir, 0) / kOutputMarker, "{}");
  const std::string path = getenv("PATH");
  setenv("PATH", ((dir / "bin").string() + ":" + path).c_str(), 1);
  const auto tasks = jobs::QueryTasks("10", 6, dir);
  setenv("PATH", path.c_str(), 1);
  ASSERT_EQ(tasks.size(), 6u);
  EXPECT_EQ(tasks[0].state, "COMPLETED");
  EXPECT_TRUE(tasks[0].output_complete);
  EXPECT_EQ(tasks[1].state, "FAILED");
  EXPECT_EQ(tasks[1].exit_code, "2:0");
  EXPECT_FALSE(tasks[1].output_complete);
  for (int i : {2, 3, 5}) {
    EXPECT_EQ(tasks[i].state, "PENDING") << i;
    EXPECT_TRUE(tasks[i].Active()) << i;
  }
  EXPECT_EQ(tasks[4].state, "UNKNOWN");  // not listed: forgotten by Slurm, the output decides
  EXPECT_FALSE(tasks[0].Active() || tasks[1].Active() || tasks[4].Active());
  EXPECT_EQ(tasks[1].log, dir / "logs" / "task-1.out");
}

}  // namespace
}  // namespace hovs
