// hovs' sharded commands as Slurm array jobs: the job folder (a readable sbatch script, the submission record, the
// tasks' logs and shard outputs), the submission through sbatch, the tasks' states through squeue / scontrol, the
// wait, and the merge of the shards into the result one process would have written.
//
// Job folder J (hovs slurm submit --job-dir J; default: the command's --out + ".slurm"):
//   J/job.sbatch         #SBATCH --array=0-(N-1)[%K] ...; exec <hovs> <command> --shard $SLURM_ARRAY_TASK_ID/N
//                        --out J/shards/shard-$SLURM_ARRAY_TASK_ID  (sbatch J/job.sbatch submits it again)
//   J/submission.json    the command, shards, job id, binary, Slurm options, versions
//   J/logs/task-I.out    each task's stdout and stderr
//   J/shards/shard-I/    each task's output, complete when it holds the staged-output marker (core/io.h)
#pragma once

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hovs::jobs {

struct SlurmOptions {
  int shards = 8;
  std::string partition, time, mem;  // as sbatch takes them (empty: the cluster's default)
  int cpus = 0;                      // --cpus-per-task (0: the cluster's default)
  int array_throttle = 0;            // at most this many tasks at once (0: no limit)
  std::string job_name = "hovs";
  void Check(const std::string& where) const;
};

// A hovs command line that can be sharded: its subcommand ("dataset"), the arguments without --out, the output.
struct ShardedCommand {
  std::string name;
  std::vector<std::string> args;  // starting with the subcommand, without --out and its value
  std::filesystem::path out;      // where the merged result goes
};
// Throws hovs::Error naming the problem: not a shardable command, no --out, a --shard of its own.
ShardedCommand ParseShardedCommand(const std::vector<std::string>& command_line);

// The array script: readable, self-contained (absolute paths), one task per shard.
std::string SbatchScript(const ShardedCommand& command, const SlurmOptions& options,
                         const std::filesystem::path& hovs_binary, const std::filesystem::path& job_dir);

// A program run to its end with its output captured. exit_code 127: it could not be started (not on PATH).
struct ProgramRun {
  int exit_code = 0;
  std::string output;  // stdout and stderr together
};
ProgramRun RunProgram(const std::vector<std::string>& argv);

// Submits the script with `sbatch --parsable`; returns the job id. Throws hovs::Error when sbatch is missing or
// refuses the job (with its message).
std::string SubmitScript(const std::filesystem::path& script, bool hold = false);
// scontrol release (a job submitted held) and scancel; throw hovs::Error with Slurm's reply when refused.
void ReleaseJob(const std::string& job_id);
void CancelJob(const std::string& job_id);

struct TaskState {
  int index = 0;
  std::string state = "UNKNOWN";  // Slurm's (PENDING, RUNNING, COMPLETED, FAILED, ...) or UNKNOWN once forgotten
  std::string exit_code;          // "code:signal" as scontrol reports it
  bool output_complete = false;   // the shard's folder holds a committed output
  std::filesystem::path log;
  bool Active() const;  // pending or running: the job is not over for it
};
// The state of every task of the job (scontrol, then the shard folders for tasks Slurm no longer lists).
std::vector<TaskState> QueryTasks(const std::string& job_id, int shards, const std::filesystem::path& job_dir);

// Polls until no task is active. timeout_s 0: no limit. Throws hovs::Error when the wait times out, or naming the
// first shard that failed (its state, exit code, log and the log's last line).
std::vector<TaskState> WaitForJob(const std::string& job_id, int shards, const std::filesystem::path& job_dir,
                                  double poll_s, double timeout_s);

// The job folder's submission record and the tasks' states as JSON.
nlohmann::json TasksJson(const std::vector<TaskState>& tasks);

// Joins the shard outputs into command.out (scenes::MergeDatasetShards for hovs dataset,
// study::MergeToleranceShards for hovs tolerance).
void MergeShards(const ShardedCommand& command, int shards, const std::filesystem::path& job_dir);

std::filesystem::path ShardDir(const std::filesystem::path& job_dir, int index);

}  // namespace hovs::jobs
