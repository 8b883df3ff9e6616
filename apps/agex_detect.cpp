// agex_detect: heads, hands and feet in depth frames.
//   agex_detect INPUT... [--model MODEL] [--json FILE] [--overlay FILE.png] [--jobs N]
// INPUT is a frame file, a directory of frames or an agex dataset. One frame: a JSON
// document. Several: JSON lines, one per frame, written as they finish, in parallel
// with --jobs; a rerun with the same --json skips the frames already there.

#include <agex/apps/command_line.h>
#include <agex/apps/frame_jobs.h>
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
  std::string model_path = AGEX_BUNDLED_MODEL, json_path, overlay_path;
  int jobs = 1;
  float min_confidence = 0.5f;

  po::options_description general ("agex_detect INPUT... [options]\n"
                                    "Heads, hands and feet in depth frames (.pcd, .png, .u16, directories, datasets)");
  general.add_options () ("help,h", "show this help") ("input", po::value (&inputs)->multitoken (), "inputs")
    ("model", po::value (&model_path)->default_value (model_path), "model file (default: the bundled model)")
    ("json", po::value (&json_path), "one frame: JSON document; several: JSON lines, one per frame (resumable)")
    ("overlay", po::value (&overlay_path), "overlay PNG (one frame only)")
    ("min-confidence", po::value (&min_confidence)->default_value (min_confidence, "0.5")->notifier ([] (float v) {
       if (!(v >= 0.f && v <= 1.f))
         throw std::runtime_error ("--min-confidence must lie in [0, 1]");
     }),
     "detections drawn on the overlay and printed")
    ("jobs", po::value (&jobs)->default_value (jobs), "frames processed in parallel");
  po::options_description all;
  all.add (general).add (agex::apps::frameOptionsDescription (frame_options));
  po::positional_options_description positional;
  positional.add ("input", -1);

  try
  {
    if (!agex::apps::parseCommandLine (argc, argv, all, positional))
      return 0;
    if (inputs.empty ())
      throw std::runtime_error ("no INPUT given (see --help)");
    if (jobs < 1)
      throw std::runtime_error ("--jobs must be at least 1");
    const auto model = std::make_shared<const agex::DetectorModel> (agex::DetectorModel::load (model_path));
    model->requireKind (agex::DetectorKind::Agex, model_path);
    agex::InputFiles read ({model_path});
    const std::vector<agex::apps::FrameJob> job_list = agex::apps::collectFrameJobs (inputs, read, "agex_detect");
    const bool single = inputs.size () == 1 && !std::filesystem::is_directory (inputs[0]);
    using Kind = agex::apps::OutputKind;
    if (!json_path.empty ())
      agex::apps::checkOutputPath (json_path, single ? Kind::JsonDocument : Kind::JsonLines, read);
    if (!overlay_path.empty () && !single)
      throw std::runtime_error ("--overlay takes a single frame");
    if (!overlay_path.empty ())
      agex::apps::checkOutputPath (overlay_path, Kind::Png, read);

    auto process = [&] (const agex::apps::FrameJob &job, cv::Mat *overlay) {
      const auto start = std::chrono::steady_clock::now ();
      const agex::Frame frame = agex::loadFrame (job.path, frame_options);
      agex::BodyPartDetector<pcl::PointXYZ> detector;
      detector.setModel (model);
      detector.setInputCloud (frame.cloud);
      std::vector<agex::BodyPartDetection> detections;
      detector.compute (detections);
      const agex::DepthPipelineResult &prepared = detector.getIntermediate ();
      nlohmann::json doc = {{"frame", job.name}, {"path", job.path}, {"width", frame.cloud->width},
                            {"height", frame.cloud->height}, {"detections", nlohmann::json::array ()}};
      for (const auto &d : detections)
        doc["detections"].push_back (agex::toJson (d));
      doc["ms"] = nlohmann::json::object ();
      for (const auto &[stage, ms] : prepared.ms)
        if (stage != "total")
          doc["ms"][stage] = ms;
      doc["ms"]["total"] = std::chrono::duration<double, std::milli> (std::chrono::steady_clock::now () - start).count ();
      if (overlay)
        *overlay = agex::apps::renderDetections (*frame.cloud, prepared.meshes, detections, min_confidence);
      return doc;
    };

    if (single)
    {
      cv::Mat overlay;
      const nlohmann::json doc = process (job_list[0], overlay_path.empty () ? nullptr : &overlay);
      if (!json_path.empty ())
        agex::apps::writeJson (json_path, doc);
      else
        std::cout << doc.dump (2) << "\n";
      if (!overlay_path.empty ())
        agex::apps::writePng (overlay_path, overlay);
      for (const auto &d : doc["detections"])
        if (d["confidence"].get<float> () >= min_confidence)
          std::cerr << "  " << d["class"].get<std::string> () << " " << d["confidence"].get<float> () << " at pixel ("
                    << d["pixel"][0] << ", " << d["pixel"][1] << ")\n";
      return 0;
    }
    std::unique_ptr<agex::apps::ResultsFile> results;
    if (!json_path.empty ())
      results = std::make_unique<agex::apps::ResultsFile> (json_path, "agex_detect");
    agex::apps::runFrameBatch (job_list, results.get (), jobs,
                               [&] (const agex::apps::FrameJob &job) { return process (job, nullptr); });
    return 0;
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_detect: error: " << e.what () << "\n";
    return 1;
  }
}
