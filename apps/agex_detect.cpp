// agex_detect: heads, hands and feet in depth frames.
//   agex_detect INPUT... [--model MODEL] [--detector-mode agex|forest] [--forest PATH] [--json FILE]
//               [--overlay FILE.png] [--parts-overlay FILE.png] [--jobs N] [--shard K/N]
//   agex_detect --merge PART... --json FILE
//   agex_detect --device openni2[:URI]|replay:PATH [--fps F] [--json FILE]
// INPUT is a frame file, a directory of frames or an agex dataset. One frame: a JSON
// document. Several: JSON lines, one per frame, written as they finish, in parallel
// with --jobs; a rerun with the same --json skips the frames already there. Under mpirun the
// ranks share the frames (doc/batch.md); --device processes a camera's frames as they arrive.

#include <agex/apps/batch_runs.h>
#include <agex/apps/detect_flags.h>
#include <agex/apps/detect_runs.h>
#include <agex/apps/live_runs.h>

#include <filesystem>
#include <iostream>
#include <memory>

int
main (int argc, char **argv)
{
  agex::apps::DetectFlags flags;
  std::unique_ptr<agex::apps::ProcessGroup> group;  // MPI, when run by mpirun: to the end of main
  try
  {
    group = agex::apps::joinProcessGroup (argc, argv);
    if (!agex::apps::parseDetectFlags (argc, argv, flags))
      return 0;
    if (!flags.merge_parts.empty ())
      return agex::apps::mergeResultParts (flags.merge_parts, flags.json_path, "agex_detect"), 0;
    const agex::apps::LoadedDetector loaded = agex::apps::loadDetector (flags.detector);
    if (!flags.parts_overlay_path.empty () && !loaded.forest)
      throw std::runtime_error ("--parts-overlay needs --forest");
    agex::InputFiles read;
    for (const auto &file : loaded.files)
      std::filesystem::is_directory (file) ? read.addTree (file) : read.add (file);
    const std::vector<agex::apps::FrameJob> jobs = agex::apps::collectFrameJobs (flags.inputs, read, "agex_detect");
    const bool single = flags.inputs.size () == 1 && !std::filesystem::is_directory (flags.inputs[0]);
    agex::apps::checkDetectOutputs (flags, single, read);

    agex::apps::DetectorPool detectors (loaded);  // one per thread, kept from frame to frame
    if (!flags.device.empty ())
      return agex::apps::runLiveDetection (flags.device, flags.fps, flags.frame_options, flags.json_path, flags.jobs,
                                           "agex_detect", [&] (const agex::SourceFrame &f) {
                                             return agex::apps::detectFrame ({f.name, f.path}, detectors, flags,
                                                                             nullptr, nullptr, &f);
                                           });
    if (single && group->rank () > 0)
      return 0;  // one frame: rank 0's
    if (single)
      return agex::apps::detectSingleFrame (jobs[0], loaded, flags), 0;
    agex::apps::runDetectionBatch (jobs, flags.json_path, flags.jobs, flags.shard, *group, "agex_detect",
                                   [&] (const agex::apps::FrameJob &job) {
                                     return agex::apps::detectFrame (job, detectors, flags);
                                   });
    return 0;
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_detect: error: " << e.what () << "\n";
    return 1;
  }
}
