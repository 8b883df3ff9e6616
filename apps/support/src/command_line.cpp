#include <agex/apps/command_line.h>

#include <boost/program_options/parsers.hpp>
#include <boost/program_options/variables_map.hpp>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <system_error>
#include <thread>
#include <vector>

#include <unistd.h>

namespace po = boost::program_options;

namespace agex
{
namespace apps
{
int
runWorkers (int jobs, std::size_t work_items, const std::function<void ()> &worker)
{
  const std::size_t wanted = std::max<std::size_t> (1, std::min<std::size_t> (std::max (jobs, 1), work_items));
  std::vector<std::thread> threads;
  try
  {
    while (threads.size () < wanted)
      threads.emplace_back (worker);
  }
  catch (const std::system_error &)
  {
    if (threads.empty ())
      throw;
    std::cerr << "warning: the system gave only " << threads.size () << " of " << wanted << " threads\n";
  }
  for (auto &t : threads)
    t.join ();
  return static_cast<int> (threads.size ());
}

std::string
bundledDataFile (const std::string &relative)
{
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink ("/proc/self/exe", ec);
  if (!ec)
  {
    const auto installed = exe.parent_path ().parent_path () / AGEX_INSTALL_DATADIR / "agex" / relative;
    if (std::filesystem::is_regular_file (installed, ec))
      return installed.string ();
  }
  return std::string (AGEX_SOURCE_DATA_DIR) + "/" + relative;
}

const std::string kBundledModelFile = bundledDataFile ("models/agex_bonn.yml");
const std::string kBundledFrameFile = bundledDataFile ("frames/bonn_1_002.png");
const std::string kBundledAgexModelFile = bundledDataFile ("models/agex_bonn_agex.yml");
const std::string kBundledSlidingWindowModelFile = bundledDataFile ("models/agex_bonn_sw.yml");
const std::string kBundledLandmarkModelFile = bundledDataFile ("models/agex_contour_landmarks.dat");

bool
parseCommandLine (int argc, char **argv, const po::options_description &options,
                  const po::positional_options_description &positional)
{
  return parseCommandLine (argc, argv, options, positional, nullptr);
}

bool
parseCommandLine (int argc, char **argv, const po::options_description &options,
                  const po::positional_options_description &positional, std::vector<std::string> *given)
{
  po::variables_map vm;
  // No guessing from a prefix: boost would take --mode for --model and read a file the user
  // never named.
  const int style = po::command_line_style::default_style & ~po::command_line_style::allow_guessing;
  po::store (po::command_line_parser (argc, argv).options (options).positional (positional).style (style).run (), vm);
  if (vm.count ("help"))
  {
    std::cout << options << "\n";
    return false;
  }
  po::notify (vm);
  if (given)
  {
    given->clear ();
    for (const auto &[name, value] : vm)
      if (!value.defaulted ())
        given->push_back (name);
  }
  return true;
}

Progress::Progress (std::string what, std::size_t total)
  : what_ (std::move (what)), total_ (total), terminal_ (::isatty (2) != 0)
{
}

void
Progress::step (std::size_t done)
{
  if (terminal_)
  {
    std::cerr << "\r  " << what_ << " " << done << "/" << total_ << (done >= total_ ? "\n" : "") << std::flush;
    return;
  }
  if (done >= next_report_ || done >= total_)
  {
    std::cerr << "  " << what_ << " " << done << "/" << total_ << "\n";
    next_report_ = done + std::max<std::size_t> (1, total_ / 10);
  }
}
}  // namespace apps
}  // namespace agex
