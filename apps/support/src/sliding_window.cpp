#include <agex/apps/sliding_window.h>

#include <agex/classification/patch_classifier.h>
#include <agex/classification/sliding_window_detector.h>

namespace agex
{
namespace apps
{
DetectorModel
loadDetectorModel (const std::string &path, DetectorKind expected)
{
  auto classifier = std::make_shared<agex::PatchClassifier> (agex::PatchClassifier::load (path));
  DetectorModel model;
  try
  {
    model.settings = DetectorSettings::fromJson (classifier->metadata ());
  }
  catch (const std::runtime_error &e)
  {
    throw std::runtime_error (path + ": " + e.what ());
  }
  model.settings.requireDetector (expected, path);
  model.classifier = classifier;
  return model;
}

std::vector<Detection>
detectBodyPartsSlidingWindow (const PipelineResult &prepared,
                              const std::shared_ptr<const agex::PatchClassifier> &classifier,
                              const DetectorSettings &settings, std::size_t *windows)
{
  if (windows)
    *windows = 0;
  std::vector<Detection> detections;
  if (!prepared.filtered || prepared.meshes.empty ())
    return detections;
  pcl::IndicesPtr surface (new pcl::Indices);
  for (const auto &mesh : prepared.meshes)
    surface->insert (surface->end (), mesh.indices.begin (), mesh.indices.end ());
  agex::SlidingWindowDetector<pcl::PointXYZ> detector;
  detector.setInputCloud (prepared.filtered);
  detector.setIndices (surface);
  detector.setClassifier (classifier);
  detector.setStride (settings.sliding_window.stride);
  detector.setScales (settings.sliding_window.scales);
  detector.setSuppressionRadius (settings.patch.suppression_radius);
  std::vector<agex::WindowDetection> found;
  detector.detect (found);
  if (windows)
    *windows = detector.getWindowCount ();
  for (const auto &w : found)
  {
    Detection d;
    d.part = static_cast<BodyPart> (w.cls);
    d.confidence = w.confidence;
    d.margin = w.margin;
    d.point.getVector3fMap () = w.position;
    d.point.orientation[0] = d.point.orientation[1] = d.point.orientation[2] = 0.f;
    d.point.u = w.u;
    d.point.v = w.v;
    d.point.rank = 0;
    d.point.mesh = -1;
    d.scale = w.scale;
    detections.push_back (d);
  }
  return detections;
}
}  // namespace apps
}  // namespace agex
