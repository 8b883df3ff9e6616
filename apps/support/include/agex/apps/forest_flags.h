#pragma once
// What agex_train_forest (and the fused detector's training) shares: the forest trainer's and
// the weak labels' flags, training frames from datasets, and training with a progress bar.

#include <agex/classification/body_part_forest.h>
#include <agex/classification/body_part_forest_trainer.h>
#include <agex/detection/part_label_training.h>

#include <boost/program_options/options_description.hpp>

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace agex
{
namespace apps
{
/** --trees --max-depth --features --thresholds --pixels-per-frame --offset-range
  * --unary-probability --min-samples-leaf --min-gain --no-balance --dilation --seed --threads */
boost::program_options::options_description forestTrainerOptions (BodyPartForestTrainerParams &params,
                                                                  bool &no_balance);
/** Applies --no-balance and checks every trainer setting's range (a setting that would make
  * training take days or terabytes is refused before any frame is read).
  * \throws std::runtime_error naming the flag */
void finishForestTrainerOptions (BodyPartForestTrainerParams &params, bool no_balance);

/** --head-reach ... --beyond-tip */
boost::program_options::options_description weakLabelOptions (WeakPartLabelParams &weak);

/** \brief The training frames of datasets (DIR[@SEQ,...]; keyframes only if asked), with
  * their focal lengths, and a progress line per dataset. \return per dataset the frames used
  * \throws std::runtime_error when no frame is usable */
nlohmann::json collectForestTrainingFrames (const std::vector<std::string> &datasets, bool keyframes,
                                            const DepthPipelineParams &pipeline, const WeakPartLabelParams &weak,
                                            bool raw_depth, std::vector<BodyPartTrainingFrame> &frames);

struct TrainedForest
{
  BodyPartForest::Ptr forest;
  double seconds = 0.0;
  std::array<std::size_t, 4> samples{};  ///< head, hand, foot, other body
};
/** Trains with a progress bar (tree levels) on standard error. */
TrainedForest trainForest (const std::vector<BodyPartTrainingFrame> &frames, const BodyPartForestTrainerParams &params);

/** The training command, parameters, weak-label rule, sample counts and time, as a forest's metadata. */
nlohmann::json forestTrainingMetadata (int argc, char **argv, const BodyPartForestTrainerParams &params,
                                       const WeakPartLabelParams &weak, const TrainedForest &trained);

/** "3 trees, 8221 leaves, 393 KiB". */
std::string describeForest (const BodyPartForest &forest);
}  // namespace apps
}  // namespace agex
