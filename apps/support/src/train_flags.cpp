#include <agex/apps/train_flags.h>

#include <agex/apps/output_guard.h>

#include <agex/apps/command_line.h>
#include <agex/apps/dataset_selection.h>
#include <agex/detection/body_part_detector.h>
#include <agex/apps/pipeline_flags.h>
#include <agex/io/atomic_file.h>

#include <boost/program_options.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace agex
{
namespace apps
{
namespace
{
/** The forests of --fused: --forest, stored in the model relative to it, and --dataset-forest. */
void
loadForests (const std::string &forest_path, const std::vector<std::string> &dataset_forests, TrainFlags &flags)
{
  flags.choice.forest = BodyPartForest::load (forest_path);
  // Stored relative to the model, so model and forest move together.
  const fs::path dir = fs::absolute (flags.out).parent_path ();
  flags.settings.forest_file = fs::relative (fs::absolute (forest_path), dir).string ();
  flags.settings.forest_bytes = fs::file_size (forest_path);
  for (const auto &pair : dataset_forests)
  {
    const auto eq = pair.rfind ('=');
    if (eq == std::string::npos ||
        std::find (flags.datasets.begin (), flags.datasets.end (), pair.substr (0, eq)) == flags.datasets.end ())
      throw std::runtime_error ("--dataset-forest " + pair + ": expected DIR[@SEQ,...]=FOREST with a DIR[@SEQ,...] "
                                "given as --dataset");
    flags.choice.dataset_forests[pair.substr (0, eq)] = BodyPartForest::load (pair.substr (eq + 1));
  }
}

void
checkRanges (const TrainFlags &flags)
{
  const TrainingChoice &choice = flags.choice;
  const PatchClassifierParams &classifier = flags.classifier_params;
  if (!(choice.radius > 0.f && choice.radius <= 1.f) || choice.random_negatives < 0 || choice.random_negatives > 10000 ||
      choice.window_negatives < 0 || choice.window_negatives > 10000 || choice.jitter < 0 || choice.jitter > 1000 ||
      !(choice.jitter_radius >= 0.f && choice.jitter_radius <= 1.f) || classifier.weak_count < 1 ||
      classifier.weak_count > 100000 || classifier.dictionary.fragments_per_class < 1 ||
      classifier.dictionary.fragments_per_class > 100000 || !(choice.background_ratio >= 0.f) ||
      choice.background_ratio > 1000.f)
    throw std::runtime_error ("--radius must lie in (0, 1], --random-negatives and --window-negatives in [0, 10000], "
                              "--jitter in [0, 1000], --jitter-radius in [0, 1], --weak-count and --fragments in [1, 100000], "
                              "--background-ratio in [0, 1000]");
  const PatchGeometry &patch = flags.patch;
  if (patch.size < 3 || patch.size > 41 || !(patch.extent > 0.f && patch.extent <= 5.f) ||
      !(patch.clamp > 0.f && patch.clamp <= 5.f))
    throw std::runtime_error ("--patch-size must lie in [3, 41], --patch-extent and --patch-clamp in (0, 5]");
}
}  // namespace

namespace
{
/** \brief Refuses, before any frame is read, a --cascade-for model the flags would not
  * reproduce the examples of: another detector kind, patch geometry, detector or pipeline
  * setting, or (fused) forest. */
void
checkCascadeModel (const TrainFlags &flags)
{
  const DetectorModel model = DetectorModel::load (flags.cascade_for);
  const std::string what = "--cascade-for " + flags.cascade_for + ": ";
  const DetectorSettings &trained = model.settings ();
  if (trained.kind != flags.settings.kind)
    throw std::runtime_error (what + "a model of the " + detectorKindName (trained.kind) +
                              " detector, and these flags collect " + detectorKindName (flags.settings.kind) +
                              " examples (give the flags it was trained with)");
  const PatchGeometry &g = model.patchGeometry ();
  const auto near = [] (float a, float b) { return std::fabs (a - b) <= 1e-5f * std::max (1.f, std::fabs (b)); };
  if (g.size != flags.patch.size || !near (g.extent, flags.patch.extent) || !near (g.clamp, flags.patch.clamp))
    throw std::runtime_error (what + "trained on " + std::to_string (g.size) + "-cell patches " +
                              std::to_string (g.extent) + " m wide, clamp " + std::to_string (g.clamp) +
                              " m; give its --patch-size, --patch-extent and --patch-clamp");
  if (trained.kind == DetectorKind::Fused && trained.forest_bytes != flags.settings.forest_bytes)
    throw std::runtime_error (what + "trained with another forest than --forest (" + trained.forest_file + ", " +
                              std::to_string (trained.forest_bytes) + " bytes)");
  nlohmann::json a = trained.toJson (), b = flags.settings.toJson ();
  for (nlohmann::json *doc : {&a, &b})
    if (doc->contains ("fused"))
    {
      (*doc)["fused"].erase ("forest");
      (*doc)["fused"].erase ("forest_bytes");
      (*doc)["fused"].erase ("window");  // the detector's, not the examples'
      (*doc)["fused"].erase ("window_weight");
    }
  if (a != b)
  {
    const nlohmann::json diff = nlohmann::json::diff (a, b);
    throw std::runtime_error (what + "trained with other settings than these flags give (first: " +
                              (diff.empty () ? std::string ("?") : diff.front ().value ("path", std::string ("?"))) +
                              "); give the flags it was trained with");
  }
}
}  // namespace

bool
parseTrainFlags (int argc, char **argv, TrainFlags &flags)
{
  DetectorSettings &settings = flags.settings;
  PatchGeometry &patch = flags.patch;
  PatchClassifierParams &classifier_params = flags.classifier_params;
  TrainingChoice &choice = flags.choice;
  std::vector<std::string> vector_flags, dataset_forests;
  std::string forest_path, window_path;
  float window_weight = -1.f;  // not given
  bool sliding_window = false, fused = false;

  po::options_description general ("agex_train --dataset DIR[@SEQ,...] [--dataset ...] --out MODEL [options]\n"
                                    "Trains the body-part classifier on labelled agex datasets");
  general.add_options () ("help,h", "show this help")
    ("dataset", po::value (&flags.datasets)->multitoken (), "dataset directory, optionally @sequences (e.g. bonn@1,2,3)")
    ("out", po::value (&flags.out), "model file to write")
    ("cascade-for", po::value (&flags.cascade_for),
     "MODEL: keep MODEL's classifier and settings and fit only its soft cascade to the examples these flags "
     "collect (give the flags MODEL was trained with); written to --out")
    ("keyframes", po::bool_switch (&choice.keyframes), "train on keyframes only")
    ("radius", po::value (&choice.radius)->default_value (choice.radius, "0.1"), "metres from a labelled tip for a positive")
    ("random-negatives", po::value (&choice.random_negatives)->default_value (choice.random_negatives),
     "random surface points per frame added as negatives (AGEX models)")
    ("background-ratio", po::value (&choice.background_ratio)->default_value (choice.background_ratio, "0"),
     "keep at most this many background examples per positive, chosen at random (0: all)")
    ("weak-count", po::value (&classifier_params.weak_count)->default_value (classifier_params.weak_count),
     "boosting rounds (decision stumps) per class")
    ("fragments", po::value (&classifier_params.dictionary.fragments_per_class)
                      ->default_value (classifier_params.dictionary.fragments_per_class),
     "dictionary fragments cut per class")
    ("seed", po::value (&choice.seed)->default_value (choice.seed), "random seed (fragments, negatives)")
    ("patch-size", po::value (&patch.size)->default_value (patch.size), "patch cells per side (<= 41)")
    ("patch-extent", po::value (&patch.extent)->default_value (patch.extent, "0.6"), "patch width, metres")
    ("patch-clamp", po::value (&patch.clamp)->default_value (patch.clamp, "0.3"), "relative depth clamp, metres")
    ("suppression-radius", po::value (&settings.suppression_radius)->default_value (settings.suppression_radius, "0.15"),
     "detection: metres within which one detection of a class is kept (stored in the model)");
  po::options_description baseline ("Sliding-window baseline (agex::SlidingWindowDetector)");
  baseline.add_options () ("sliding-window", po::bool_switch (&sliding_window),
                           "train the sliding-window baseline: upright patches centred on the labelled tips "
                           "against random patches of the rest of the person")
    ("window-negatives", po::value (&choice.window_negatives)->default_value (choice.window_negatives),
     "random person pixels per frame (farther than 1.5 radius from every tip) as negatives")
    ("jitter", po::value (&choice.jitter)->default_value (choice.jitter), "extra positives per tip, at random pixels near it")
    ("jitter-radius", po::value (&choice.jitter_radius)->default_value (choice.jitter_radius, "0.04"),
     "metres from the tip for the extra positives")
    ("window-stride", po::value (&settings.sliding_window.stride)->default_value (settings.sliding_window.stride),
     "detection: pixels between window centres, 1-64; -1: --window-stride-metres at the person's depth (stored in "
     "the model)")
    ("window-stride-metres", po::value (&settings.sliding_window.stride_metres)
                                 ->default_value (settings.sliding_window.stride_metres, "0.015"),
     "detection: metres between window centres with --window-stride -1 (stored in the model)")
    ("window-scales", po::value (&settings.sliding_window.scales)->multitoken ()->default_value (settings.sliding_window.scales, "1"),
     "detection: window extents over --patch-extent (stored in the model)");
  po::options_description fusion ("Fused detector (AGEX points and a forest's part modes)");
  fusion.add_options () ("fused", po::bool_switch (&fused), "train the fused detector (needs --forest)")
    ("forest", po::value (&forest_path), "the body-part forest (an agex forest file) whose features it learns")
    ("dataset-forest", po::value (&dataset_forests)->multitoken (),
     "DIR[@SEQ,...]=FOREST: the frames of that --dataset are labelled by FOREST (one trained without them) "
     "instead of --forest, so the classifier sees the forest as on new frames (cross-fitting)")
    ("forest-stride", po::value (&settings.forest_stride)->default_value (settings.forest_stride),
     "pixel stride of the forest pass (stored in the model; 0: by the focal length, 1 at 144x176, 2 at 640x480)")
    ("merge-radius", po::value (&settings.fused.merge_radius)->default_value (settings.fused.merge_radius, "0.03"),
     "metres within which candidates are one (stored in the model)")
    ("window-model", po::value (&window_path),
     "a sliding-window model whose confidences the detector blends into the candidates' (stored in the model "
     "relative to it; it may still be training: the detector loads it)")
    ("window-weight", po::value (&window_weight),
     "with --window-model: each class's confidence is (1 - w) fused + w window, w in [0, 1] (default 0.3; stored "
     "in the model)");
  po::options_description all;
  all.add (general).add (baseline).add (fusion).add (pipelineOptionsDescription (settings.pipeline, vector_flags));

  if (!parseCommandLine (argc, argv, all, po::positional_options_description ()))
    return false;
  finishPipelineOptions (vector_flags, settings.pipeline);
  if (flags.datasets.empty () || flags.out.empty ())
    throw std::runtime_error ("--dataset and --out are required (see --help)");
  if (sliding_window && fused)
    throw std::runtime_error ("--sliding-window and --fused are different detectors: choose one");
  if (fused != !forest_path.empty ())
    throw std::runtime_error ("--fused needs --forest, and --forest is for --fused");
  choice.kind = settings.kind = sliding_window ? DetectorKind::SlidingWindow
                                               : fused ? DetectorKind::Fused : DetectorKind::Agex;
  if (!window_path.empty () && !fused)
    throw std::runtime_error ("--window-model is for --fused");
  if (window_path.empty () && window_weight != -1.f)
    throw std::runtime_error ("--window-weight is for --window-model");
  if (!window_path.empty ())
  {
    settings.window_weight = window_weight == -1.f ? BodyPartDetector<pcl::PointXYZ>::kDefaultWindowWeight : window_weight;
    if (!(settings.window_weight >= 0.f && settings.window_weight <= 1.f))
      throw std::runtime_error ("--window-weight must lie in [0, 1]");
    if (fs::absolute (window_path).lexically_normal () == fs::absolute (flags.out).lexically_normal ())
      throw std::runtime_error ("--window-model " + window_path + " is --out: the fused model would replace it");
    settings.window_file = fs::relative (fs::absolute (window_path), fs::absolute (flags.out).parent_path ()).string ();
  }
  else
    settings.window_weight = 0.f;
  if (fused)
    loadForests (forest_path, dataset_forests, flags);
  else if (!dataset_forests.empty ())
    throw std::runtime_error ("--dataset-forest is for --fused");
  settings.validate ([] (const std::string &key) {
    return key.rfind ("pipeline.", 0) == 0 ? pipelineFlagName (key.substr (9)) : "setting " + key;
  });
  checkRanges (flags);
  if (fs::is_directory (flags.out))
    throw std::runtime_error ("--out " + flags.out + ": a directory, not a model file");
  InputFiles read;  // checked before hours of training: the model must not land on its inputs
  for (const auto &spec : flags.datasets)
    read.addTree (selectDataset (spec, false).dataset.directory ());
  if (!forest_path.empty ())
    read.add (forest_path);
  if (!window_path.empty ())
    read.add (window_path);
  if (!flags.cascade_for.empty ())
    read.add (flags.cascade_for);
  for (const auto &pair : dataset_forests)
    read.add (pair.substr (pair.rfind ('=') + 1));
  checkOutputPath (flags.out, OutputKind::Model, read);
  if (!flags.cascade_for.empty ())
  {
    checkCascadeModel (flags);
    // The model keeps its window model (named relative to --out now) unless --window-model is given.
    const DetectorModel model = DetectorModel::load (flags.cascade_for);
    if (window_path.empty () && !model.windowPath ().empty ())
    {
      settings.window_file =
          fs::relative (fs::absolute (model.windowPath ()), fs::absolute (flags.out).parent_path ()).string ();
      settings.window_weight = model.settings ().window_weight;
    }
  }
  classifier_params.dictionary.seed = choice.seed;
  return true;
}
}  // namespace apps
}  // namespace agex
