#pragma once
// The sliding-window baseline as the apps run it (agex::SlidingWindowDetector on the
// pipeline's segmented frame) and loading a model of either kind.

#include <agex/apps/body_parts.h>

#include <memory>
#include <random>
#include <string>
#include <vector>

namespace agex
{
namespace apps
{
/** A model file and the settings it was trained with. */
struct DetectorModel
{
  std::shared_ptr<const agex::PatchClassifier> classifier;
  DetectorSettings settings;
};

/** \brief Loads a model and checks its detector kind.
  * \throws agex::ModelError (damaged model) or std::runtime_error naming the file (a
  *         model of the other kind, malformed settings) */
DetectorModel loadDetectorModel (const std::string &path, DetectorKind expected);

/** \brief Sliding-window detections on a prepared frame: windows centred on the pixels of
  * the pipeline's meshes (the segmented person, as AGEX sees it), with the model's stride,
  * scales and patch geometry, suppressed per class within patch.suppression_radius.
  * Detections are sorted by confidence; their point holds the window centre (no
  * orientation), u, v, and rank 0. */
std::vector<Detection> detectBodyPartsSlidingWindow (const PipelineResult &prepared,
                                                     const std::shared_ptr<const agex::PatchClassifier> &classifier,
                                                     const DetectorSettings &settings,
                                                     std::size_t *windows = nullptr);

}  // namespace apps
}  // namespace agex
