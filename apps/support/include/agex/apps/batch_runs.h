#pragma once
// Runs over many frames split among processes: the ranks of an MPI job (mpirun -n N) or the
// tasks of a job array (--shard K/N), each writing its own JSON-lines part that a merge joins
// in input order (agex_detect), and the frame shares of agex_eval.

#include <agex/apps/frame_jobs.h>
#include <agex/apps/process_group.h>

#include <nlohmann/json.hpp>

#include <cstddef>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace agex
{
namespace apps
{
/** --shard K/N: this run does the K-th (0-based) of N parts of the frames. */
struct Shard
{
  int index = 0;
  int count = 1;
  bool given = false;  ///< --shard was given (even 0/1): lines carry their frame's index
};

/** \brief Parses "K/N" (0 <= K < N <= 100000). \throws std::runtime_error naming --shard */
Shard parseShard (const std::string &text);

/** The frames [first, last) of part k of n of `frames` frames: n contiguous blocks whose
  * sizes differ by at most one, so that a merge of the parts in order is input order. */
std::pair<std::size_t, std::size_t> shardRange (std::size_t frames, int k, int n);

/** \brief agex_detect's run over several frames: runFrameBatch on the frames of this
  * process's share, process giving each frame's document.
  *
  * - Alone (no --shard, one process): as runFrameBatch, appending to json_path (or standard
  *   output when empty), resumable.
  * - --shard K/N: the K-th part of the frames; each line also gets "batch": {"index": its
  *   frame's position among all the inputs' frames, "frames": their number}, which
  *   mergeResultParts orders by. json_path (or standard output) is this part's file.
  * - Under mpirun -n N: rank r does the r-th part into "<json_path>.part-r-of-N"; once every
  *   rank is done, rank 0 merges the parts with json_path's earlier frames into json_path
  *   (atomically, in input order) and removes the parts. Frames already in json_path or in
  *   any part of an earlier run (whatever its N) are not done again, so an interrupted run
  *   resumes. json_path is required.
  * \throws std::runtime_error: the first failure of this process, or of another rank (on
  *         rank 0), saying what is kept for a rerun */
void runDetectionBatch (const std::vector<FrameJob> &jobs, const std::string &json_path, int threads,
                        const Shard &shard, ProcessGroup &group, const std::string &app,
                        const std::function<nlohmann::json (const FrameJob &)> &process);

/** \brief agex_detect --merge: the frame results of parts (JSON-lines files of --shard runs,
  * or any results files) and of out's earlier frames, each frame once, into out, atomically:
  * lines without a batch index first (out's, then the parts' in the order given), then the
  * indexed ones in index order, without their "batch" field. With order, frames it holds take
  * their position in it instead. A frame in several files is taken from an indexed line if one
  * has it, else from the first.
  * \throws std::runtime_error naming the file: not a results file (a line that is not a frame
  *         result; a torn last line is skipped with a warning), parts of different runs (two
  *         frame counts, or two frames with one index), or frames missing (indices no part
  *         holds, the first few named); out is then left as it was */
void mergeResultParts (const std::vector<std::string> &parts, const std::string &out, const std::string &app,
                       const std::vector<FrameJob> *order = nullptr);
}  // namespace apps
}  // namespace agex
