// agex_bench: how fast is agex?
//   agex_bench [INPUT...]: for each frame, at full resolution and in the 144x176
//     portrait view of the source paper, times AGEX_k with the incremental multi-source
//     Dijkstra and with the naive k-full-runs reference on the same meshes, and the depth
//     pipeline stage by stage. Single-threaded.
//   agex_bench --dataset DIR: the whole detector (pipeline, patches, classifier) on every
//     frame of a dataset, stage by stage, on one core; then frames per second with --jobs.
//   agex_bench --dataset DIR --compare-with BUILD_DIR: this build and another in turns,
//     every stage's ratio.

#include <agex/apps/bench_compare.h>
#include <agex/apps/bench_flags.h>
#include <agex/apps/bench_runs.h>
#include <agex/apps/command_line.h>
#include <agex/apps/dataset_selection.h>
#include <agex/apps/output.h>
#include <agex/apps/output_guard.h>
#include <agex/io/atomic_file.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>

namespace
{
/** --compare-with: both builds in turns, their reports in a scratch folder removed after. */
nlohmann::json
compareWith (const agex::apps::BenchFlags &flags, int argc, char **argv)
{
  agex::apps::BenchComparison comparison;
  comparison.this_program = std::filesystem::read_symlink ("/proc/self/exe").string ();
  comparison.other_program = agex::apps::otherBenchProgram (flags.compare_with);
  comparison.arguments = agex::apps::forwardedBenchArguments (argc, argv);
  comparison.rounds = flags.rounds;
  comparison.model = std::filesystem::absolute (flags.detector.model).string ();
  comparison.passes = flags.passes;
  std::string scratch = (std::filesystem::temp_directory_path () / "agex_bench_compare_XXXXXX").string ();
  if (!mkdtemp (scratch.data ()))
    throw std::runtime_error ("cannot make a scratch folder in " + std::filesystem::temp_directory_path ().string () +
                              ": " + std::strerror (errno));
  comparison.work_dir = scratch;
  try
  {
    nlohmann::json doc = agex::apps::compareBenchBuilds (comparison);
    doc["dataset"] = flags.dataset_spec;
    std::filesystem::remove_all (scratch);
    return doc;
  }
  catch (...)
  {
    std::cerr << "agex_bench: the runs' reports and output are kept in " << scratch << "\n";
    throw;
  }
}
}  // namespace

int
main (int argc, char **argv)
{
  agex::apps::BenchFlags flags;
  try
  {
    if (!agex::apps::parseBenchFlags (argc, argv, flags))
      return 0;
    nlohmann::json doc;
    if (!flags.dataset_spec.empty ())
    {
      if (!flags.inputs.empty ())
        throw std::runtime_error ("give either frame files or --dataset, not both");
      if (!flags.json_path.empty ())
      {
        agex::InputFiles read (
            agex::apps::datasetFiles (agex::apps::selectDataset (flags.dataset_spec, false).dataset));
        read.add (flags.detector.model);
        read.add (flags.detector.window_model);
        agex::apps::checkOutputPath (flags.json_path, "agex_bench report", agex::apps::benchReportRecogniser (), read);
      }
      if (!flags.compare_with.empty ())
        doc = compareWith (flags, argc, argv);
      else
        doc = agex::apps::benchDataset (flags.dataset_spec, flags.keyframes_only,
                                        agex::apps::loadDetector (flags.detector), flags.passes, flags.jobs,
                                        static_cast<std::size_t> (flags.memory_frames));
    }
    else
    {
      if (flags.inputs.empty ())
        flags.inputs.push_back (AGEX_BUNDLED_FRAME);
      if (!flags.json_path.empty ())
      {
        agex::InputFiles read (flags.inputs);
        read.add (flags.detector.model);
        read.add (flags.detector.window_model);
        agex::apps::checkOutputPath (flags.json_path, "agex_bench report", agex::apps::benchReportRecogniser (), read);
      }
      doc = agex::apps::benchFrames (flags.inputs, flags.frame_options, flags.params, flags.k, flags.repeat,
                                     !flags.no_portrait);
    }
    if (!flags.json_path.empty ())
      agex::apps::writeJson (flags.json_path, doc);
    return 0;
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_bench: error: " << e.what () << "\n";
    return 1;
  }
}
