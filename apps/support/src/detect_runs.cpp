#include <agex/apps/detect_runs.h>

#include <agex/apps/live_runs.h>
#include <agex/apps/output.h>
#include <agex/apps/output_guard.h>
#include <agex/detection/body_part_detector.h>

#include <chrono>
#include <iostream>

namespace agex
{
namespace apps
{
DetectorPool::DetectorPool (const LoadedDetector &loaded) : loaded_ (loaded) {}

DetectorPool::~DetectorPool () = default;

std::size_t
DetectorPool::size () const
{
  std::lock_guard<std::mutex> lock (mutex_);
  return all_.size ();
}

BodyPartDetector<pcl::PointXYZ> *
DetectorPool::take ()
{
  {
    std::lock_guard<std::mutex> lock (mutex_);
    if (!idle_.empty ())
    {
      BodyPartDetector<pcl::PointXYZ> *detector = idle_.back ();
      idle_.pop_back ();
      return detector;
    }
  }
  auto detector = std::make_unique<BodyPartDetector<pcl::PointXYZ>> ();
  loaded_.configure (*detector);
  std::lock_guard<std::mutex> lock (mutex_);
  all_.push_back (std::move (detector));
  return all_.back ().get ();
}

void
DetectorPool::giveBack (BodyPartDetector<pcl::PointXYZ> *detector)
{
  std::lock_guard<std::mutex> lock (mutex_);
  idle_.push_back (detector);
}

nlohmann::json
detectFrame (const FrameJob &job, DetectorPool &detectors, const DetectFlags &flags, cv::Mat *overlay,
             cv::Mat *parts_overlay, const SourceFrame *live)
{
  const auto start = std::chrono::steady_clock::now ();
  const Frame frame = live ? liveFrame (*live) : loadFrame (job.path, flags.frame_options);
  return detectors.with ([&] (BodyPartDetector<pcl::PointXYZ> &detector) {
    // A PCD carries no intrinsics: the detector estimates them (0), whatever the last frame had.
    if (frame.from_depth_image)
      detector.setFocalLength (static_cast<float> (frame.intrinsics.fx), static_cast<float> (frame.intrinsics.fy));
    else
      detector.setFocalLength (0.f, 0.f);
    detector.setInputCloud (frame.cloud);
    std::vector<BodyPartDetection> detections;
    detector.compute (detections);
    const DepthPipelineResult &prepared = detector.getIntermediate ();
    nlohmann::json doc = {{"frame", job.name}, {"path", job.path}, {"width", frame.cloud->width},
                          {"height", frame.cloud->height}, {"detector_mode", detectors.loaded ().mode_name},
                          {"detections", nlohmann::json::array ()}};
    for (const auto &d : detections)
      doc["detections"].push_back (toJson (d));
    doc["persons"] = personsJson (prepared.person_info);
    doc["ms"] = nlohmann::json::object ();
    for (const auto &[stage, ms] : prepared.ms)
      if (stage != "total")
        doc["ms"][stage] = ms;
    doc["ms"]["total"] = std::chrono::duration<double, std::milli> (std::chrono::steady_clock::now () - start).count ();
    if (overlay)
      *overlay = renderDetections (*frame.cloud, prepared.meshesInInput (), detections, flags.min_confidence);
    if (parts_overlay)
      // The part labels are the working frame's pixels (DepthPipelineParams::working_spacing).
      *parts_overlay = renderPartLabels (prepared.frame ? *prepared.frame : *frame.cloud, detector.getPartLabels (),
                                         detector.getPartModes (), {});
    return doc;
  });
}

void
checkDetectOutputs (const DetectFlags &flags, bool single, const InputFiles &read)
{
  if (!flags.json_path.empty ())
    checkOutputPath (flags.json_path, single ? OutputKind::JsonDocument : OutputKind::JsonLines, read);
  for (const auto &png : {flags.overlay_path, flags.parts_overlay_path})
  {
    if (!png.empty () && !single)
      throw std::runtime_error ("--overlay and --parts-overlay take a single frame");
    if (!png.empty ())
      checkOutputPath (png, OutputKind::Png, read);
  }
}

void
detectSingleFrame (const FrameJob &job, const LoadedDetector &loaded, const DetectFlags &flags)
{
  cv::Mat overlay, parts_overlay;
  DetectorPool detectors (loaded);
  const nlohmann::json doc = detectFrame (job, detectors, flags, flags.overlay_path.empty () ? nullptr : &overlay,
                                          flags.parts_overlay_path.empty () ? nullptr : &parts_overlay);
  {
    // The frame's JSON and overlays belong together: another run's set is written before or
    // after this one, never between its files.
    const OutputSetClaim claim ({flags.json_path, flags.overlay_path, flags.parts_overlay_path});
    if (!flags.json_path.empty ())
      writeJson (flags.json_path, doc);
    if (!flags.overlay_path.empty ())
      writePng (flags.overlay_path, overlay);
    if (!flags.parts_overlay_path.empty ())
      writePng (flags.parts_overlay_path, parts_overlay);
  }
  if (flags.json_path.empty ())
    std::cout << doc.dump (2) << "\n";
  for (const auto &d : doc["detections"])
    if (d["confidence"].get<float> () >= flags.min_confidence)
      std::cerr << "  " << d["class"].get<std::string> () << " " << d["confidence"].get<float> () << " at pixel ("
                << d["pixel"][0] << ", " << d["pixel"][1] << ")\n";
}
}  // namespace apps
}  // namespace agex
