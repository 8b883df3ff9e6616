#pragma once
// agex_train's flags: the datasets and the model file, how examples are mined, the classifier,
// the patch geometry, the detector's settings stored in the model and the forests of a fused
// detector, checked (and the forests loaded) before anything is trained.

#include <agex/apps/training_runs.h>
#include <agex/classification/patch_classifier.h>
#include <agex/detection/detector_model.h>

#include <string>
#include <vector>

namespace agex
{
namespace apps
{
struct TrainFlags
{
  TrainFlags () { settings.pipeline.k = 11; }  // the centroid and 10 extrema per mesh: positives and hard negatives

  std::vector<std::string> datasets;  ///< DIR[@SEQ,...]
  std::string out;                    ///< the model file
  std::string cascade_for;            ///< a trained model whose soft cascade alone is fitted (empty: train)
  DetectorSettings settings;
  PatchGeometry patch{41, 0.6f, 0.3f};
  PatchClassifierParams classifier_params;
  TrainingChoice choice;  ///< the forests of a fused detector loaded
};

/** \brief Parses agex_train's command line into flags, checks every setting's range and the
  * detector chosen (--sliding-window, --fused with --forest and --dataset-forest), loads the
  * forests, and refuses an --out that is a directory or would land on an input.
  * \return false when --help was given (the help is printed)
  * \throws std::runtime_error, std::invalid_argument or boost::program_options::error naming
  *         the flag */
bool parseTrainFlags (int argc, char **argv, TrainFlags &flags);
}  // namespace apps
}  // namespace agex
