#pragma once

#include <boost/program_options/options_description.hpp>
#include <boost/program_options/positional_options.hpp>

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace agex
{
namespace apps
{
/** \brief Parses the command line into the variables bound in options and runs
  * their notifiers. Prints the options and returns false when --help was given. A flag is
  * taken only by its whole name, never guessed from a prefix.
  * \throws boost::program_options::error on an unknown or malformed flag */
bool parseCommandLine (int argc, char **argv, const boost::program_options::options_description &options,
                       const boost::program_options::positional_options_description &positional);
/** As above; given (not null) receives the long names of the flags on the command line
  * (defaults and positional arguments included only when given). */
bool parseCommandLine (int argc, char **argv, const boost::program_options::options_description &options,
                       const boost::program_options::positional_options_description &positional,
                       std::vector<std::string> *given);

/** A file shipped with agex (relative to data/, e.g. "models/agex_bonn.yml"): the installed
  * copy, <prefix>/share/agex/<relative>, when this executable runs from <prefix>/bin,
  * else the one in the source tree it was built from. */
std::string bundledDataFile (const std::string &relative);
/** bundledDataFile ("models/agex_bonn.yml"), the apps' default model (AGEX_BUNDLED_MODEL). */
extern const std::string kBundledModelFile;
/** bundledDataFile ("frames/bonn_1_002.png"), agex_bench's default frame (AGEX_BUNDLED_FRAME). */
extern const std::string kBundledFrameFile;
/** bundledDataFile ("models/agex_bonn_agex.yml"), the AGEX-point model (agex_eval compare's default). */
extern const std::string kBundledAgexModelFile;
/** bundledDataFile ("models/agex_bonn_sw.yml"), the sliding-window baseline's default model. */
extern const std::string kBundledSlidingWindowModelFile;
/** bundledDataFile ("models/agex_contour_landmarks.dat"), agex_landmarks' default model. */
extern const std::string kBundledLandmarkModelFile;

/** \brief Runs worker on min(jobs, work_items) threads (at least one) and joins them.
  * If the system refuses some of the threads, runs on those it got; if it refuses all,
  * throws std::system_error. \return the threads used */
int runWorkers (int jobs, std::size_t work_items, const std::function<void ()> &worker);

/** \brief Progress of long work on standard error: a line updated in place on a
  * terminal, a line per tenth of the work otherwise (logs stay short). */
class Progress
{
public:
  Progress (std::string what, std::size_t total);
  void step (std::size_t done);

private:
  std::string what_;
  std::size_t total_;
  bool terminal_;
  std::size_t next_report_ = 0;
};
}  // namespace apps
}  // namespace agex
