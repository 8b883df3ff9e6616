#include <agex/apps/forest_flags.h>

#include <agex/apps/command_line.h>
#include <agex/apps/dataset_selection.h>

#include <boost/program_options.hpp>

#include <chrono>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace po = boost::program_options;

namespace agex
{
namespace apps
{
namespace
{
void
require (bool ok, const std::string &message)
{
  if (!ok)
    throw std::runtime_error (message);
}
}  // namespace

po::options_description
forestTrainerOptions (BodyPartForestTrainerParams &params, bool &no_balance)
{
  po::options_description desc ("Forest (agex::BodyPartForestTrainer)");
  desc.add_options () ("trees", po::value (&params.trees)->default_value (params.trees), "trees (1-64)")
    ("max-depth", po::value (&params.max_depth)->default_value (params.max_depth), "deepest tree level (1-24)")
    ("features", po::value (&params.features_per_node)->default_value (params.features_per_node),
     "candidate offset pairs per node (1-10000)")
    ("thresholds", po::value (&params.thresholds_per_feature)->default_value (params.thresholds_per_feature),
     "candidate thresholds per feature (1-1000)")
    ("pixels-per-frame", po::value (&params.pixels_per_frame)->default_value (params.pixels_per_frame),
     "labelled pixels sampled per frame and tree (1-1000000)")
    ("offset-range", po::value (&params.offset_range)->default_value (params.offset_range),
     "largest offset component, pixel*metres at the 525 px reference focal length (1-1000)")
    ("unary-probability", po::value (&params.unary_probability)->default_value (params.unary_probability, "0.3"),
     "share of features whose second probe is the pixel itself")
    ("min-samples-leaf", po::value (&params.min_samples_per_leaf)->default_value (params.min_samples_per_leaf),
     "fewest samples a split may leave on a side")
    ("min-gain", po::value (&params.min_gain)->default_value (params.min_gain, "1e-4"), "smallest gain (bits) of a split")
    ("no-balance", po::bool_switch (&no_balance), "do not weigh classes inversely to their frequency")
    ("dilation", po::value (&params.foreground_dilation)->default_value (params.foreground_dilation),
     "the forest also sees the real depth this many pixels around the body (PCL's person mask: 2; 0-8)")
    ("seed", po::value (&params.seed)->default_value (params.seed), "random seed")
    ("threads", po::value (&params.threads)->default_value (params.threads), "training threads (1-256)");
  return desc;
}

void
finishForestTrainerOptions (BodyPartForestTrainerParams &params, bool no_balance)
{
  params.balance_classes = !no_balance;
  require (params.trees >= 1 && params.trees <= BodyPartForest::kMaxTrees, "--trees must lie in [1, 64]");
  require (params.max_depth >= 1 && params.max_depth <= BodyPartForest::kMaxDepth, "--max-depth must lie in [1, 24]");
  require (params.features_per_node >= 1 && params.features_per_node <= 10000, "--features must lie in [1, 10000]");
  require (params.thresholds_per_feature >= 1 && params.thresholds_per_feature <= 1000,
           "--thresholds must lie in [1, 1000]");
  require (params.pixels_per_frame >= 1 && params.pixels_per_frame <= 1000000,
           "--pixels-per-frame must lie in [1, 1000000]");
  require (params.offset_range >= 1 && params.offset_range <= 1000, "--offset-range must lie in [1, 1000]");
  require (params.unary_probability >= 0.f && params.unary_probability <= 1.f,
           "--unary-probability must lie in [0, 1]");
  require (params.min_samples_per_leaf >= 1 && params.min_samples_per_leaf <= 1000000,
           "--min-samples-leaf must lie in [1, 1000000]");
  require (params.min_gain >= 0.0 && params.min_gain <= 10.0, "--min-gain must lie in [0, 10] bits");
  require (params.foreground_dilation >= 0 && params.foreground_dilation <= 8, "--dilation must lie in [0, 8]");
  require (params.threads >= 1 && params.threads <= 256, "--threads must lie in [1, 256]");
}

po::options_description
weakLabelOptions (WeakPartLabelParams &weak)
{
  po::options_description desc ("Weak labels from tips and bases (frames without a part-label image)");
  desc.add_options ()
    ("head-reach", po::value (&weak.reach[0])->default_value (weak.reach[0], "0.25"), "metres from the tip towards the base")
    ("hand-reach", po::value (&weak.reach[1])->default_value (weak.reach[1], "0.2"), "metres from the tip towards the base")
    ("foot-reach", po::value (&weak.reach[2])->default_value (weak.reach[2], "0.22"), "metres from the tip towards the base")
    ("head-radius", po::value (&weak.radius[0])->default_value (weak.radius[0], "0.12"), "metres from the tip-base axis")
    ("hand-radius", po::value (&weak.radius[1])->default_value (weak.radius[1], "0.06"), "metres from the tip-base axis")
    ("foot-radius", po::value (&weak.radius[2])->default_value (weak.radius[2], "0.07"), "metres from the tip-base axis")
    ("beyond-tip", po::value (&weak.beyond_tip)->default_value (weak.beyond_tip, "0.03"),
     "metres a part extends past its tip");
  return desc;
}

nlohmann::json
collectForestTrainingFrames (const std::vector<std::string> &datasets, bool keyframes,
                             const DepthPipelineParams &pipeline, const WeakPartLabelParams &weak, bool raw_depth,
                             std::vector<BodyPartTrainingFrame> &frames)
{
  nlohmann::json sources = nlohmann::json::array ();
  for (const auto &spec : datasets)
  {
    const DatasetSelection selection = selectDataset (spec, keyframes);
    Progress progress ("frames of " + spec, selection.frame_ids.size ());
    std::size_t used = 0, exact = 0;
    for (std::size_t i = 0; i < selection.frame_ids.size (); ++i)
    {
      PartLabelledFrame labelled;
      if (partLabelledFrame (selection.dataset, selection.frame_ids[i], pipeline, weak, raw_depth, labelled))
      {
        BodyPartTrainingFrame f;
        f.cloud = labelled.cloud;
        f.body = std::move (labelled.body);
        f.classes = std::move (labelled.classes);
        // The cloud is the working frame (DepthPipelineParams::working_spacing): f / stride.
        const auto stride = static_cast<float> (labelled.prepared.stride);
        f.fx = static_cast<float> (selection.dataset.info ().intrinsics.fx) / stride;
        f.fy = static_cast<float> (selection.dataset.info ().intrinsics.fy) / stride;
        frames.push_back (std::move (f));
        ++used;
        exact += labelled.exact ? 1 : 0;
      }
      progress.step (i + 1);
    }
    sources.push_back ({{"dataset", spec}, {"frames", used}, {"frames_with_label_images", exact}});
  }
  if (frames.empty ())
    throw std::runtime_error ("no usable training frame (a part-label image, or labels with every tip visible, "
                              "and a body)");
  return sources;
}

TrainedForest
trainForest (const std::vector<BodyPartTrainingFrame> &frames, const BodyPartForestTrainerParams &params)
{
  BodyPartForestTrainer trainer;
  trainer.setParams (params);
  std::unique_ptr<Progress> bar;
  const auto start = std::chrono::steady_clock::now ();
  TrainedForest trained;
  trained.forest = trainer.train (frames, [&] (std::size_t done, std::size_t total) {
    if (!bar)
      bar = std::make_unique<Progress> ("tree levels", total);
    bar->step (done);
  });
  trained.seconds = std::chrono::duration<double> (std::chrono::steady_clock::now () - start).count ();
  const auto &sampled = trainer.sampledPerClass ();
  for (std::size_t c = 0; c < trained.samples.size () && c < sampled.size (); ++c)
    trained.samples[c] = sampled[c];
  return trained;
}

nlohmann::json
forestTrainingMetadata (int argc, char **argv, const BodyPartForestTrainerParams &params,
                        const WeakPartLabelParams &weak, const TrainedForest &trained)
{
  std::ostringstream command;
  for (int i = 0; i < argc; ++i)
    command << (i ? " " : "") << argv[i];
  const auto &s = trained.samples;
  return {{"command", command.str ()},
          {"samples", {{"head", s[0]}, {"hand", s[1]}, {"foot", s[2]}, {"other_body", s[3]}}},
          {"params",
           {{"trees", params.trees}, {"max_depth", params.max_depth}, {"features", params.features_per_node},
            {"thresholds", params.thresholds_per_feature}, {"pixels_per_frame", params.pixels_per_frame},
            {"offset_range", params.offset_range}, {"unary_probability", params.unary_probability},
            {"min_samples_leaf", params.min_samples_per_leaf}, {"min_gain", params.min_gain},
            {"balance_classes", params.balance_classes}, {"dilation", params.foreground_dilation},
            {"seed", params.seed}}},
          {"weak_labels", {{"reach", weak.reach}, {"radius", weak.radius}, {"beyond_tip", weak.beyond_tip}}},
          {"seconds", trained.seconds}};
}

std::string
describeForest (const BodyPartForest &forest)
{
  std::size_t leaves = 0;
  for (const auto &t : forest.trees ())
    leaves += t.leafCount ();
  std::ostringstream out;
  out << forest.trees ().size () << " trees, " << leaves << " leaves, " << forest.memoryBytes () / 1024 << " KiB";
  return out.str ();
}
}  // namespace apps
}  // namespace agex
