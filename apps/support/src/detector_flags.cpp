#include <agex/apps/detector_flags.h>

#include <boost/program_options.hpp>

#include <filesystem>
#include <stdexcept>

namespace po = boost::program_options;

namespace agex
{
namespace apps
{
po::options_description
detectorOptionsDescription (DetectorChoice &choice, const std::string &model_default)
{
  choice.model = model_default;
  po::options_description desc ("Detector");
  desc.add_options ()
    ("model", po::value (&choice.model)->default_value (model_default),
     "model file: the classifier and the pipeline settings (default: the bundled model)")
    ("detector-mode", po::value (&choice.mode)->default_value (choice.mode, "the model's kind"),
     "agex: an AGEX model's classifier on AGEX points; fused: a fused model (AGEX points and the forest's part "
     "modes, one classifier); forest: the per-pixel forest's part modes alone")
    ("forest", po::value (&choice.forest),
     "per-pixel body-part forest: an agex forest file, a PCL tree file (.txt, .txt.bz2) or a directory of them "
     "(e.g. ../shared/data/pcl_people)")
    ("forest-stride", po::value (&choice.forest_stride)->default_value (choice.forest_stride)->notifier ([] (int v) {
       if (v < 0 || v > 8)
         throw std::runtime_error ("--forest-stride must lie in [0, 8]");
     }),
     "forest: one evaluated pixel per stride x stride cell (0: by the focal length, 2 at 640x480)")
    ("cascade-min-confidence",
     po::value (&choice.cascade_min_confidence)->default_value (choice.cascade_min_confidence, "0.05")->notifier ([] (float v) {
       if (!(v >= 0.f && v < 1.f))
         throw std::runtime_error ("--cascade-min-confidence must lie in [0, 1)");
     }),
     "the classifier's soft cascade drops candidates it rejects at this confidence without computing all their "
     "features (0: every candidate classified in full; models trained before the cascade have none)")
    ("cascade-miss-rate",
     po::value (&choice.cascade_miss_rate)->default_value (choice.cascade_miss_rate, "0")->notifier ([] (float v) {
       if (!(v >= 0.f && v <= 0.5f))
         throw std::runtime_error ("--cascade-miss-rate must lie in [0, 0.5]");
     }),
     "the fraction of each class's training positives reaching the cascade's level (the largest at most "
     "--cascade-min-confidence) it may reject (0: none)")
    ("tip-radius",
     po::value (&choice.tip_refinement.radius)->default_value (choice.tip_refinement.radius)->notifier ([] (float v) {
       if (!(v >= 0.f && v <= 0.5f))
         throw std::runtime_error ("--tip-radius must lie in [0, 0.5] metres");
     }),
     "fused models: each hand and foot detection moves up to this far (metres) to its part's extremity, the most "
     "salient AGEX point of its mesh there that the classifier also takes for that part (0: off)")
    ("tip-min-confidence",
     po::value (&choice.tip_refinement.min_relative_confidence)
       ->default_value (choice.tip_refinement.min_relative_confidence)
       ->notifier ([] (float v) {
         if (!(v > 0.f && v <= 1.f))
           throw std::runtime_error ("--tip-min-confidence must lie in (0, 1]");
       }),
     "the extremity's confidence for the detection's class, as a fraction of the detection's, at least this")
    ("window-model", po::value (&choice.window_model),
     "fused models: a sliding-window model (agex_train --sliding-window) whose confidences at each candidate's "
     "pixel blend into the fused classifier's (default: the one the fused model names, if any)")
    ("window-weight",
     po::value (&choice.window_weight)->notifier ([] (float v) {
       if (!(v >= 0.f && v <= 1.f))
         throw std::runtime_error ("--window-weight must lie in [0, 1]");
     }),
     "fused models with a window model: each class's confidence is (1 - w) fused + w window (0: off; default: "
     "the weight the fused model names, else 0.3)")
    ("forest-input", po::value (&choice.forest_input)->default_value (choice.forest_input)->notifier ([] (const std::string &v) {
       ForestInput input;
       if (!parseForestInput (v, input))
         throw std::runtime_error ("--forest-input must be automatic, persons or meshes, not '" + v + "'");
     }),
     "forest mode: the pixels the forest labels: persons (as segmented, at the frame's own depth), meshes (after "
     "the cleaning stages, as before) or automatic (persons for PCL's forests, meshes for ours: what each was trained on)")
    ("forest-parts", po::value (&choice.forest_parts)->default_value (choice.forest_parts)->notifier ([] (const std::string &v) {
       PartProposals proposals;
       if (!parsePartProposals (v, proposals))
         throw std::runtime_error ("--forest-parts must be blobs or modes, not '" + v + "'");
     }),
     "forest mode: labels to parts: blobs (PCL-style connected blobs at their extremities) or modes (mean shift, "
     "as before)");
  return desc;
}

void
LoadedDetector::configure (BodyPartDetector<pcl::PointXYZ> &detector) const
{
  detector.setModel (model);
  detector.setForest (forest);
  detector.setMode (mode);
  detector.setForestStride (forest_stride);
  detector.setCascadeMinConfidence (cascade_min_confidence);
  detector.setCascadeMissRate (cascade_miss_rate);
  detector.setTipRefinement (tip_refinement);
  detector.setWindowRescoring (window_model, window_weight);
  detector.setForestParts (forest_parts);
}

LoadedDetector
loadDetector (const DetectorChoice &choice, DetectorKind kind)
{
  LoadedDetector loaded;
  if (!choice.mode.empty () && choice.mode != "agex" && choice.mode != "fused" && choice.mode != "forest")
    throw std::runtime_error ("unknown --detector-mode '" + choice.mode + "' (expected agex, fused or forest)");
  loaded.mode = choice.mode == "forest" ? DetectorMode::Forest : DetectorMode::Model;
  loaded.model = std::make_shared<const DetectorModel> (DetectorModel::load (choice.model));
  const DetectorKind model_kind = loaded.model->settings ().kind;
  if (choice.mode == "agex")
    loaded.model->requireKind (kind == DetectorKind::Fused ? DetectorKind::Agex : kind, choice.model);
  if (choice.mode == "fused")
    loaded.model->requireKind (DetectorKind::Fused, choice.model);
  loaded.files.push_back (choice.model);
  std::string forest = choice.forest;
  if (forest.empty () && model_kind == DetectorKind::Fused)
    forest = loaded.model->forestPath ();  // a fused model's own forest
  if (loaded.mode == DetectorMode::Forest && forest.empty ())
    throw std::runtime_error ("--detector-mode forest needs --forest (a forest file or a directory of PCL trees)");
  if (!forest.empty ())
  {
    loaded.forest = BodyPartForest::load (forest);
    loaded.files.push_back (forest);
    loaded.forest_file = forest;
    std::error_code ec;
    if (model_kind == DetectorKind::Fused && !choice.forest.empty () && choice.mode != "forest" &&
        (!std::filesystem::is_regular_file (forest, ec) ||
         std::filesystem::file_size (forest, ec) != loaded.model->settings ().forest_bytes))
      throw std::runtime_error ("--forest " + forest + " is not the forest " + choice.model +
                                " was trained with (" + loaded.model->settings ().forest_file + ")");
  }
  loaded.forest_stride = choice.forest_stride;
  loaded.cascade_min_confidence = choice.cascade_min_confidence;
  loaded.cascade_miss_rate = choice.cascade_miss_rate;
  loaded.tip_refinement = choice.tip_refinement;
  WindowChoice window;
  try
  {
    window = chooseWindowModel (*loaded.model, choice.model,
                                model_kind == DetectorKind::Fused && loaded.mode == DetectorMode::Model,
                                choice.window_model, choice.window_weight,
                                BodyPartDetector<pcl::PointXYZ>::kDefaultWindowWeight, "--window-model", "--window-weight");
  }
  catch (const std::invalid_argument &e)
  {
    throw std::runtime_error (e.what ());  // a combination of flags, as the other flag errors here
  }
  if (!window.path.empty ())
  {
    loaded.window_model = loadWindowModel (window.path, *loaded.model, window.own ? choice.model : "");
    loaded.window_weight = window.weight;
    loaded.files.push_back (window.path);
    loaded.window_file = window.path;
  }
  if (!parseForestInput (choice.forest_input, loaded.forest_parts.input))
    throw std::runtime_error ("--forest-input must be automatic, persons or meshes, not '" + choice.forest_input + "'");
  if (!parsePartProposals (choice.forest_parts, loaded.forest_parts.proposals))
    throw std::runtime_error ("--forest-parts must be blobs or modes, not '" + choice.forest_parts + "'");
  loaded.mode_name = loaded.mode == DetectorMode::Forest ? "forest" : detectorKindName (model_kind);
  return loaded;
}
}  // namespace apps
}  // namespace agex
