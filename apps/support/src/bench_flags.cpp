#include <agex/apps/bench_flags.h>

#include <agex/apps/command_line.h>
#include <agex/apps/pipeline_flags.h>

#include <boost/program_options.hpp>

#include <stdexcept>

namespace po = boost::program_options;

namespace agex
{
namespace apps
{
bool
parseBenchFlags (int argc, char **argv, BenchFlags &flags)
{
  std::vector<std::string> vector_flags;
  po::options_description general ("agex_bench [INPUT...] [options]\n"
                                    "agex_bench --dataset DIR[@SEQ,...] [--model MODEL] [--jobs N] [--json FILE]\n"
                                    "Times AGEX (incremental vs naive) and the depth pipeline per frame, or the whole\n"
                                    "detector over a dataset");
  general.add_options () ("help,h", "show this help")
    ("dataset", po::value (&flags.dataset_spec), "time the detector on this dataset's frames (DIR or DIR@1,2,...)")
    ("keyframes", po::bool_switch (&flags.keyframes_only), "with --dataset: keyframes only")
    ("passes", po::value (&flags.passes)->default_value (flags.passes), "with --dataset: timed runs per frame")
    ("jobs", po::value (&flags.jobs)->default_value (flags.jobs), "with --dataset: threads for the throughput run")
    ("input", po::value (&flags.inputs)->multitoken (), "frame files (default: the bundled Bonn frame)")
    ("bench-k", po::value (&flags.k)->default_value (flags.k), "k for the incremental vs naive comparison")
    ("repeat", po::value (&flags.repeat)->default_value (flags.repeat), "timed runs per measurement")
    ("no-portrait", po::bool_switch (&flags.no_portrait), "skip the 144x176 portrait view of 640x480 frames")
    ("json", po::value (&flags.json_path), "write the figures as JSON here")
    ("compare-with", po::value (&flags.compare_with),
     "with --dataset: another build directory; run its bin/agex_bench and this one in turns, one thread each, and "
     "print every stage's ratio this / other")
    ("rounds", po::value (&flags.rounds)->default_value (flags.rounds), "with --compare-with: runs of each build")
    ("memory-frames", po::value (&flags.memory_frames)->default_value (flags.memory_frames),
     "with --dataset: then run one detector over this many frames (the selected ones in turn) and report its "
     "resident memory after the first pass and as it goes (0: no such run)");
  po::options_description all;
  all.add (general).add (detectorOptionsDescription (flags.detector, kBundledModelFile))
     .add (frameOptionsDescription (flags.frame_options))
     .add (pipelineOptionsDescription (flags.params, vector_flags));
  po::positional_options_description positional;
  positional.add ("input", -1);

  if (!parseCommandLine (argc, argv, all, positional))
    return false;
  finishPipelineOptions (vector_flags, flags.params);
  if (flags.k < 1 || flags.repeat < 1 || flags.passes < 1 || flags.jobs < 1 || flags.rounds < 1)
    throw std::runtime_error ("--bench-k, --repeat, --passes, --jobs and --rounds must be at least 1");
  if (flags.repeat > 100000 || flags.passes > 1000 || flags.jobs > 1024 || flags.rounds > 100)
    throw std::runtime_error ("--repeat must be at most 100000, --passes 1000, --jobs 1024 and --rounds 100");
  if (flags.memory_frames < 0 || flags.memory_frames > 10000000)
    throw std::runtime_error ("--memory-frames must lie in 0..10,000,000");
  if (flags.memory_frames > 0 && (flags.dataset_spec.empty () || !flags.compare_with.empty ()))
    throw std::runtime_error ("--memory-frames runs the detector over a --dataset, without --compare-with");
  if (!flags.compare_with.empty () && flags.dataset_spec.empty ())
    throw std::runtime_error ("--compare-with times the detector over a --dataset: give one");
  if (flags.k > 1000)
    throw std::runtime_error ("--bench-k must be at most 1000 (the naive reference runs a full Dijkstra per point)");
  return true;
}
}  // namespace apps
}  // namespace agex
