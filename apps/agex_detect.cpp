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
#include <agex/apps/command_line.h>
#include <agex/apps/detector_flags.h>
#include <agex/apps/frame_jobs.h>
#include <agex/apps/live_runs.h>
#include <agex/apps/output.h>
#include <agex/apps/output_guard.h>
#include <agex/apps/pipeline_flags.h>
#include <agex/apps/results_file.h>
#include <agex/detection/body_part_detector.h>
#include <agex/io/frame_io.h>

#include <boost/program_options.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>

namespace po = boost::program_options;

int
main (int argc, char **argv)
{
  agex::FrameOptions frame_options;
  std::vector<std::string> inputs;
  agex::apps::DetectorChoice choice;
  std::string json_path, overlay_path, parts_overlay_path;
  int jobs = 1;
  float min_confidence = 0.5f;
  std::string shard, device;
  std::vector<std::string> merge_parts;
  double fps = 30.0;

  po::options_description general ("agex_detect INPUT... [options]\n"
                                    "Heads, hands and feet in depth frames (.pcd, .png, .u16, directories, datasets)");
  general.add_options () ("help,h", "show this help") ("input", po::value (&inputs)->multitoken (), "inputs")
    ("json", po::value (&json_path), "one frame: JSON document; several: JSON lines, one per frame (resumable)")
    ("overlay", po::value (&overlay_path), "overlay PNG (one frame only)")
    ("parts-overlay", po::value (&parts_overlay_path),
     "the forest's part map over the depth frame as PNG (one frame only; needs --forest)")
    ("min-confidence", po::value (&min_confidence)->default_value (min_confidence, "0.5")->notifier ([] (float v) {
       if (!(v >= 0.f && v <= 1.f))
         throw std::runtime_error ("--min-confidence must lie in [0, 1]");
     }),
     "detections drawn on the overlay and printed")
    ("jobs", po::value (&jobs)->default_value (jobs), "frames processed in parallel")
    ("shard", po::value (&shard), "K/N: only the K-th (0-based) of N equal parts of the frames, for job arrays")
    ("merge", po::value (&merge_parts)->multitoken (), "join the --json parts of --shard runs into --json, in input order")
    ("device", po::value (&device), "openni2, openni2:URI or replay:PATH: process a live source's frames as they arrive")
    ("fps", po::value (&fps)->default_value (fps), "frames per second of --device replay:PATH");
  po::options_description all;
  all.add (general).add (agex::apps::detectorOptionsDescription (choice, AGEX_BUNDLED_MODEL))
     .add (agex::apps::frameOptionsDescription (frame_options));
  po::positional_options_description positional;
  positional.add ("input", -1);

  std::unique_ptr<agex::apps::ProcessGroup> group;  // MPI, when run by mpirun: to the end of main
  try
  {
    group = agex::apps::joinProcessGroup (argc, argv);
    if (!agex::apps::parseCommandLine (argc, argv, all, positional))
      return 0;
    if (!merge_parts.empty () && !inputs.empty ())
      throw std::runtime_error ("--merge takes the parts, and no INPUT");
    if (!merge_parts.empty ())
      return agex::apps::mergeResultParts (merge_parts, json_path, "agex_detect"), 0;
    if (!device.empty () && !inputs.empty ())
      throw std::runtime_error ("--device is the input: give no INPUT with it");
    if (inputs.empty () && device.empty ())
      throw std::runtime_error ("no INPUT given (see --help)");
    if (jobs < 1)
      throw std::runtime_error ("--jobs must be at least 1");
    const agex::apps::Shard part = shard.empty () ? agex::apps::Shard () : agex::apps::parseShard (shard);
    const agex::apps::LoadedDetector loaded = agex::apps::loadDetector (choice);
    if (!parts_overlay_path.empty () && !loaded.forest)
      throw std::runtime_error ("--parts-overlay needs --forest");
    agex::InputFiles read;
    for (const auto &file : loaded.files)
      std::filesystem::is_directory (file) ? read.addTree (file) : read.add (file);
    const std::vector<agex::apps::FrameJob> job_list = agex::apps::collectFrameJobs (inputs, read, "agex_detect");
    const bool single = inputs.size () == 1 && !std::filesystem::is_directory (inputs[0]);
    using Kind = agex::apps::OutputKind;
    if (!json_path.empty ())
      agex::apps::checkOutputPath (json_path, single ? Kind::JsonDocument : Kind::JsonLines, read);
    for (const auto &png : {overlay_path, parts_overlay_path})
    {
      if (!png.empty () && !single)
        throw std::runtime_error ("--overlay and --parts-overlay take a single frame");
      if (!png.empty ())
        agex::apps::checkOutputPath (png, Kind::Png, read);
    }

    auto process = [&] (const agex::apps::FrameJob &job, cv::Mat *overlay, cv::Mat *parts_overlay,
                        const agex::SourceFrame *live = nullptr) {
      const auto start = std::chrono::steady_clock::now ();
      const agex::Frame frame = live ? agex::apps::liveFrame (*live) : agex::loadFrame (job.path, frame_options);
      agex::BodyPartDetector<pcl::PointXYZ> detector;
      loaded.configure (detector);
      if (frame.from_depth_image)  // a PCD carries no intrinsics: the detector estimates them
        detector.setFocalLength (static_cast<float> (frame.intrinsics.fx), static_cast<float> (frame.intrinsics.fy));
      detector.setInputCloud (frame.cloud);
      std::vector<agex::BodyPartDetection> detections;
      detector.compute (detections);
      const agex::DepthPipelineResult &prepared = detector.getIntermediate ();
      nlohmann::json doc = {{"frame", job.name}, {"path", job.path}, {"width", frame.cloud->width},
                            {"height", frame.cloud->height}, {"detector_mode", loaded.mode_name},
                            {"detections", nlohmann::json::array ()}};
      for (const auto &d : detections)
        doc["detections"].push_back (agex::toJson (d));
      doc["persons"] = agex::apps::personsJson (prepared.person_info);
      doc["ms"] = nlohmann::json::object ();
      for (const auto &[stage, ms] : prepared.ms)
        if (stage != "total")
          doc["ms"][stage] = ms;
      doc["ms"]["total"] = std::chrono::duration<double, std::milli> (std::chrono::steady_clock::now () - start).count ();
      if (overlay)
        *overlay = agex::apps::renderDetections (*frame.cloud, prepared.meshes, detections, min_confidence);
      if (parts_overlay)
        *parts_overlay = agex::apps::renderPartLabels (*frame.cloud, detector.getPartLabels (),
                                                       detector.getPartModes (), {});
      return doc;
    };

    if (!device.empty ())
      return agex::apps::runLiveDetection (device, fps, frame_options, json_path, jobs, "agex_detect",
                                           [&] (const agex::SourceFrame &f) {
                                             return process ({f.name, f.path}, nullptr, nullptr, &f);
                                           });
    if (single && group->rank () > 0)
      return 0;  // one frame: rank 0's
    if (single)
    {
      cv::Mat overlay, parts_overlay;
      const nlohmann::json doc = process (job_list[0], overlay_path.empty () ? nullptr : &overlay,
                                          parts_overlay_path.empty () ? nullptr : &parts_overlay);
      if (!json_path.empty ())
        agex::apps::writeJson (json_path, doc);
      else
        std::cout << doc.dump (2) << "\n";
      if (!overlay_path.empty ())
        agex::apps::writePng (overlay_path, overlay);
      if (!parts_overlay_path.empty ())
        agex::apps::writePng (parts_overlay_path, parts_overlay);
      for (const auto &d : doc["detections"])
        if (d["confidence"].get<float> () >= min_confidence)
          std::cerr << "  " << d["class"].get<std::string> () << " " << d["confidence"].get<float> () << " at pixel ("
                    << d["pixel"][0] << ", " << d["pixel"][1] << ")\n";
      return 0;
    }
    agex::apps::runDetectionBatch (job_list, json_path, jobs, part, *group, "agex_detect",
                                   [&] (const agex::apps::FrameJob &job) { return process (job, nullptr, nullptr); });
    return 0;
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_detect: error: " << e.what () << "\n";
    return 1;
  }
}
