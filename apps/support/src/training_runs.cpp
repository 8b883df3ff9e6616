#include <agex/apps/training_runs.h>

#include <agex/apps/command_line.h>
#include <agex/apps/dataset_selection.h>
#include <agex/detection/training_samples.h>

#include <array>
#include <iostream>
#include <random>

namespace agex
{
namespace apps
{
nlohmann::json
collectTrainingExamples (const std::vector<std::string> &datasets, const TrainingChoice &choice,
                         const DetectorSettings &settings, const PatchGeometry &geometry,
                         std::vector<DepthPatch> &patches, std::vector<std::vector<float>> &auxiliary,
                         std::vector<int> &classes)
{
  std::mt19937_64 rng (choice.seed);
  nlohmann::json sources = nlohmann::json::array ();
  for (const auto &spec : datasets)
  {
    const DatasetSelection selection = selectDataset (spec, choice.keyframes);
    const auto &intr = selection.dataset.info ().intrinsics;
    const float fx = static_cast<float> (intr.fx), fy = static_cast<float> (intr.fy);
    Progress progress ("frames of " + spec, selection.frame_ids.size ());
    std::size_t used = 0;
    for (std::size_t i = 0; i < selection.frame_ids.size (); ++i)
    {
      const auto &id = selection.frame_ids[i];
      const auto labels = selection.dataset.labelsOf (id);
      progress.step (i + 1);
      if (labels.empty ())
        continue;  // unlabelled frames say nothing about where parts are
      const auto prepared = runDepthPipeline (selection.dataset.loadFrame (id), settings.pipeline);
      switch (choice.kind)
      {
      case DetectorKind::SlidingWindow:
        collectWindowTrainingSamples (prepared, labels, choice.radius, choice.jitter, choice.jitter_radius,
                                      choice.window_negatives, geometry, rng, patches, classes);
        break;
      case DetectorKind::Fused:
      {
        pcl::PointCloud<BodyPartLabelPoint> part_labels;
        std::vector<PartMode> modes;
        const auto own = choice.dataset_forests.find (spec);
        // The stages ran on the working frame (DepthPipelineParams::working_spacing).
        const float working_fx = fx / static_cast<float> (prepared.stride);
        const float working_fy = fy / static_cast<float> (prepared.stride);
        labelPersonParts (prepared, own != choice.dataset_forests.end () ? own->second : choice.forest, working_fx,
                          working_fy, settings.forest_stride, part_labels, modes);
        collectFusedTrainingSamples (prepared, part_labels, modes, working_fx, settings.pipeline.up, settings.fused, labels,
                                     choice.radius, geometry, patches, auxiliary, classes);
        break;
      }
      default:
        collectTrainingSamples (prepared, labels, choice.radius, choice.random_negatives, geometry, rng, patches,
                                classes);
      }
      ++used;
    }
    sources.push_back ({{"dataset", spec}, {"frames", used}});
  }
  const std::size_t dropped = keepBackgroundAtMost (choice.background_ratio, rng, patches, auxiliary, classes);
  if (dropped > 0)
    std::cout << "background thinned to " << choice.background_ratio << " per positive: " << dropped
              << " examples dropped\n";
  return sources;
}

DetectorModel
trainDetector (const std::vector<DepthPatch> &patches, const std::vector<std::vector<float>> &auxiliary,
               const std::vector<int> &classes, const PatchClassifierParams &params, const PatchGeometry &geometry,
               const DetectorSettings &settings)
{
  if (patches.empty ())
    throw std::runtime_error ("no training examples: no labelled frame with a body in the datasets");
  std::array<int, 4> counts{};
  for (const int c : classes)
    ++counts[c < 0 ? 3 : c];
  std::cout << "training on " << patches.size () << " patches: head " << counts[0] << ", hand " << counts[1]
            << ", foot " << counts[2] << ", background " << counts[3] << "\n";
  auto classifier = std::make_shared<PatchClassifier> ();
  const auto progress = [] (int done, int total) { std::cerr << "  boosted class " << done << "/" << total << "\n"; };
  if (settings.kind == DetectorKind::Fused)
    classifier->train (patches, auxiliary, fusedFeatureNames (), classes, kBodyPartCount, params, progress);
  else
    classifier->train (patches, classes, kBodyPartCount, params, progress);
  classifier->setPatchGeometry (geometry);
  return DetectorModel (classifier, settings);
}
DetectorModel
withFittedCascade (const DetectorModel &model, const std::string &path, const DetectorSettings &settings,
                   const std::vector<DepthPatch> &patches, const std::vector<std::vector<float>> &auxiliary,
                   const std::vector<int> &classes, const PatchClassifierParams &params)
{
  if (patches.empty ())
    throw std::runtime_error ("no training examples: no labelled frame with a body in the datasets");
  auto classifier = std::make_shared<PatchClassifier> (model.classifier ());
  try
  {
    classifier->fitCascade (patches, auxiliary, classes, params.cascade_stage_ends, params.cascade_levels,
                            params.cascade_miss_rates);
  }
  catch (const std::exception &e)
  {
    throw std::runtime_error ("--cascade-for " + path + ": " + e.what ());
  }
  if (classifier->cascade ().empty ())
    throw std::runtime_error ("--cascade-for " + path + ": no cascade fits it (no stage end below its " +
                              std::to_string (classifier->params ().weak_count) + " rounds)");
  // The model's settings, with its forest named relative to --out (parseTrainFlags checked
  // that it is the forest the model was trained with), and its window model as parseTrainFlags
  // resolved it (the model's own, or --window-model's).
  DetectorSettings kept = model.settings ();
  kept.forest_file = settings.forest_file;
  kept.window_file = settings.window_file;
  kept.window_weight = settings.window_file.empty () ? 0.f : settings.window_weight;
  return DetectorModel (classifier, kept);
}
}  // namespace apps
}  // namespace agex
