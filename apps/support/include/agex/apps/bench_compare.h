#pragma once
// agex_bench --compare-with BUILD_DIR: this build's agex_bench and another build's, run in
// turns on the same dataset and settings, so that a change's speed is a ratio measured under
// the same machine load rather than two absolute times taken at different moments.

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace agex
{
namespace apps
{
/** The two programs compared and how. */
struct BenchComparison
{
  std::string this_program;   ///< this build's agex_bench
  std::string other_program;  ///< BUILD_DIR/bin/agex_bench
  /** The arguments both are run with (a --dataset run; without --json, --jobs, --model,
    * --passes, --compare-with and --rounds, which the comparison sets). */
  std::vector<std::string> arguments;
  /** The model both run, resolved here: each build's default is its own source tree's. */
  std::string model;
  int passes = 3;
  int rounds = 5;
  std::string work_dir;  ///< where the runs' reports go (an existing directory)
};

/** \brief The arguments of argv (without argv[0]) less the comparison's own flags and the ones
  * it sets for each run: --compare-with, --rounds, --json, --jobs, --model and --passes, as
  * "--flag value" or "--flag=value". */
std::vector<std::string> forwardedBenchArguments (int argc, char **argv);

/** \brief Runs the two programs rounds times each, in turns (this, other; then other, this; and
  * so on, so that neither always runs first), each with the same model and passes, --jobs 1
  * and a --json report in work_dir, and compares every stage's median: per stage, the median over the rounds of each
  * build's median, and the median of the per-round ratios this / other. Prints a table.
  * \return {"compare_with", "rounds", "stages": {stage: {"this_ms", "other_ms", "ratio"}},
  *         "total": {...}} (stages both builds time; "total" is ms_per_frame)
  * \throws std::runtime_error naming the program when a run fails or writes no report */
nlohmann::json compareBenchBuilds (const BenchComparison &comparison);

/** \brief The other build's agex_bench: BUILD_DIR/bin/agex_bench, which must be an executable
  * file. \throws std::runtime_error naming the directory */
std::string otherBenchProgram (const std::string &build_dir);
}  // namespace apps
}  // namespace agex
