#pragma once
// agex_train's work: training examples mined from labelled datasets for each detector kind
// (AGEX points, sliding windows, fused candidates), the classifier trained on them, and the
// model written with its settings and how it was made.

#include <agex/classification/body_part_forest.h>
#include <agex/detection/detector_model.h>

#include <nlohmann/json.hpp>

#include <map>
#include <string>
#include <vector>

namespace agex
{
namespace apps
{
/** How examples are mined (the flags of agex_train). */
struct TrainingChoice
{
  DetectorKind kind = DetectorKind::Agex;
  float radius = 0.10f;          ///< metres from a labelled tip for a positive
  int random_negatives = 8;      ///< AGEX: random surface points per frame as negatives
  int window_negatives = 40;     ///< sliding windows: random person pixels per frame
  int jitter = 3;                ///< sliding windows: extra positives per tip
  float jitter_radius = 0.04f;   ///< sliding windows: metres from the tip for those
  bool keyframes = false;
  /** At most this many background examples per positive, a random choice of them
    * (agex::keepBackgroundAtMost); 0 keeps all. */
  float background_ratio = 0.f;
  std::uint64_t seed = 1;
  BodyPartForest::ConstPtr forest;  ///< fused: the forest whose features the classifier learns
  /** Fused: the forest that labels the frames of a dataset argument (DIR[@SEQ,...], as given)
    * instead of `forest`: one trained without those frames, so that the classifier learns how
    * far to trust the forest on frames it has not seen (cross-fitting). */
  std::map<std::string, BodyPartForest::ConstPtr> dataset_forests;
};

/** The examples of every labelled frame of the datasets (DIR[@SEQ,...]), with a progress line
  * per dataset, the background thinned to choice.background_ratio.
  * \return per dataset the frames used */
nlohmann::json collectTrainingExamples (const std::vector<std::string> &datasets, const TrainingChoice &choice,
                                        const DetectorSettings &settings, const PatchGeometry &geometry,
                                        std::vector<DepthPatch> &patches, std::vector<std::vector<float>> &auxiliary,
                                        std::vector<int> &classes);

/** \brief Trains the classifier on the examples (auxiliary features when fused), with a line
  * per boosted class, and prints the example counts.
  * \return the model of the classifier and settings */
DetectorModel trainDetector (const std::vector<DepthPatch> &patches, const std::vector<std::vector<float>> &auxiliary,
                             const std::vector<int> &classes, const PatchClassifierParams &params,
                             const PatchGeometry &geometry, const DetectorSettings &settings);
/** \brief model with its soft cascade fitted (PatchClassifier::fitCascade) to the examples,
  * its classifier and settings unchanged but for the forest's path (settings.forest_file,
  * relative to the file it is written to).
  * \throws std::runtime_error naming path if the examples do not fit it or no cascade fits */
DetectorModel withFittedCascade (const DetectorModel &model, const std::string &path, const DetectorSettings &settings,
                                 const std::vector<DepthPatch> &patches,
                                 const std::vector<std::vector<float>> &auxiliary, const std::vector<int> &classes,
                                 const PatchClassifierParams &params);
}  // namespace apps
}  // namespace agex
