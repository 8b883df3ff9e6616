#include <agex/detection/detector_model.h>

#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>

namespace agex
{
namespace
{
std::string
formatNumber (double v)
{
  std::ostringstream out;
  out << v;
  return out.str ();
}

void
checkGeometry (const PatchGeometry &g, const std::string &source)
{
  if (g.size < 3 || g.size > DepthPatch::kMaxSize || !(g.extent > 0.f && g.extent <= 5.f) ||
      !(g.clamp > 0.f && g.clamp <= 5.f))
    throw std::invalid_argument (source + ": patch geometry size " + std::to_string (g.size) + ", extent " +
                                 formatNumber (g.extent) + " m, clamp " + formatNumber (g.clamp) +
                                 " m is outside size [3, 41], extent (0, 5], clamp (0, 5]");
}
}  // namespace

const char *
detectorKindName (DetectorKind kind)
{
  switch (kind)
  {
  case DetectorKind::SlidingWindow: return "sliding_window";
  case DetectorKind::Fused: return "fused";
  default: return "agex";
  }
}

void
DetectorSettings::validate (const std::function<std::string (const std::string &key)> &name) const
{
  pipeline.validate ([&name] (const std::string &key) { return name ("pipeline." + key); });
  if (!(suppression_radius >= 0.f && suppression_radius <= 2.f))
    throw std::invalid_argument (name ("suppression_radius") + " is " + formatNumber (suppression_radius) +
                                 ", outside [0, 2] metres");
  if (kind == DetectorKind::Fused)
  {
    fused.validate ([&name] (const std::string &key) { return name ("fused." + key); });
    if (forest_file.empty () || forest_file.size () > 4096)
      throw std::invalid_argument (name ("fused.forest") + " must name the forest the model was trained with");
    if (forest_stride < 0 || forest_stride > 8)
      throw std::invalid_argument (name ("fused.forest_stride") + " is " + std::to_string (forest_stride) +
                                   ", outside [0, 8] (0: by the focal length)");
    if (window_file.size () > 4096)
      throw std::invalid_argument (name ("fused.window") + " is longer than 4096 characters");
    if (!(window_weight >= 0.f && window_weight <= 1.f))
      throw std::invalid_argument (name ("fused.window_weight") + " is " + formatNumber (window_weight) +
                                   ", outside [0, 1]");
  }
  if (kind == DetectorKind::SlidingWindow)
  {
    if (sliding_window.stride != -1 && (sliding_window.stride < 1 || sliding_window.stride > 64))
      throw std::invalid_argument (name ("sliding_window.stride") + " is " + std::to_string (sliding_window.stride) +
                                   ", outside [1, 64] pixels (-1: sliding_window.stride_metres)");
    if (!(sliding_window.stride_metres > 0.f && sliding_window.stride_metres <= 0.5f))
      throw std::invalid_argument (name ("sliding_window.stride_metres") + " is " +
                                   formatNumber (sliding_window.stride_metres) + ", outside (0, 0.5] metres");
    if (sliding_window.scales.empty () || sliding_window.scales.size () > 16)
      throw std::invalid_argument (name ("sliding_window.scales") + " must hold 1 to 16 scales");
    for (const float s : sliding_window.scales)
      if (!(s > 0.f && s <= 10.f))
        throw std::invalid_argument (name ("sliding_window.scales") + " holds " + formatNumber (s) +
                                     ", outside (0, 10]");
  }
}

nlohmann::json
DetectorSettings::toJson () const
{
  nlohmann::json doc = {{"detector", detectorKindName (kind)},
                        {"suppression_radius", suppression_radius},
                        {"pipeline", pipeline.toJson ()}};
  if (kind == DetectorKind::SlidingWindow)
    doc["sliding_window"] = {{"stride", sliding_window.stride},
                             {"scales", sliding_window.scales},
                             {"stride_metres", sliding_window.stride_metres}};
  if (kind == DetectorKind::Fused)
    doc["fused"] = {{"merge_radius", fused.merge_radius},
                    {"min_mode_confidence", fused.min_mode_confidence},
                    {"forest", forest_file},
                    {"forest_bytes", forest_bytes},
                    {"forest_stride", forest_stride}};
  if (kind == DetectorKind::Fused && !window_file.empty ())
  {
    doc["fused"]["window"] = window_file;
    doc["fused"]["window_weight"] = window_weight;
  }
  return doc;
}

DetectorSettings
DetectorSettings::fromJson (const nlohmann::json &doc, const std::string &source)
{
  const auto name = [&source] (const std::string &key) { return source + ": " + key; };
  if (!doc.is_object ())
    throw std::invalid_argument (source + ": the model's settings are missing (not an agex detector model?)");
  DetectorSettings s;
  const auto kind = doc.find ("detector");
  if (kind != doc.end ())
  {
    if (!kind->is_string ())
      throw std::invalid_argument (name ("detector") + " must be a string");
    if (*kind == detectorKindName (DetectorKind::SlidingWindow))
      s.kind = DetectorKind::SlidingWindow;
    else if (*kind == detectorKindName (DetectorKind::Fused))
      s.kind = DetectorKind::Fused;
    else if (*kind != detectorKindName (DetectorKind::Agex))
      throw std::invalid_argument (name ("detector") + ": unknown detector '" + kind->get<std::string> () +
                                   "' (expected agex, sliding_window or fused)");
  }
  // Models written before the schema moved here kept the radius beside the patch geometry.
  const nlohmann::json *radius = nullptr;
  if (doc.contains ("suppression_radius"))
    radius = &doc["suppression_radius"];
  else if (doc.contains ("patch") && doc["patch"].is_object () && doc["patch"].contains ("suppression_radius"))
    radius = &doc["patch"]["suppression_radius"];
  if (radius)
  {
    if (!radius->is_number () || !std::isfinite (radius->get<double> ()) || std::abs (radius->get<double> ()) > 1e6)
      throw std::invalid_argument (name ("suppression_radius") + " must be a number");
    s.suppression_radius = radius->get<float> ();
  }
  if (!doc.contains ("pipeline"))
    throw std::invalid_argument (source + ": pipeline settings are missing");
  s.pipeline = DepthPipelineParams::fromJson (doc["pipeline"], source);
  if (doc.contains ("sliding_window"))
  {
    const auto &w = doc["sliding_window"];
    if (!w.is_object () || !w.contains ("stride") || !w["stride"].is_number_integer () || !w.contains ("scales") ||
        !w["scales"].is_array () || w["scales"].size () > 16)
      throw std::invalid_argument (name ("sliding_window") + " must hold an integer stride and up to 16 scales");
    const auto stride = w["stride"].get<long long> ();
    s.sliding_window.stride = stride < -1 || stride > 1000 ? 0 : static_cast<int> (stride);
    // Models written before it have a pixel stride and no stride_metres.
    if (w.contains ("stride_metres"))
    {
      if (!w["stride_metres"].is_number ())
        throw std::invalid_argument (name ("sliding_window.stride_metres") + " must be a number");
      const double metres = w["stride_metres"].get<double> ();
      s.sliding_window.stride_metres = std::isfinite (metres) && std::abs (metres) < 1e6 ? static_cast<float> (metres) : -1.f;
    }
    s.sliding_window.scales.clear ();
    for (const auto &scale : w["scales"])
    {
      if (!scale.is_number ())
        throw std::invalid_argument (name ("sliding_window.scales") + " must be numbers");
      s.sliding_window.scales.push_back (scale.get<float> ());
    }
  }
  if (s.kind == DetectorKind::Fused)
  {
    const auto it = doc.find ("fused");
    if (it == doc.end () || !it->is_object ())
      throw std::invalid_argument (name ("fused") + " is missing");
    const auto &f = *it;
    auto number = [&] (const char *key, double lo, double hi) {
      if (!f.contains (key) || !f[key].is_number ())
        throw std::invalid_argument (name (std::string ("fused.") + key) + " is missing or not a number");
      const double v = f[key].get<double> ();
      if (!(v >= lo && v <= hi))
        throw std::invalid_argument (name (std::string ("fused.") + key) + " is out of range");
      return v;
    };
    s.fused.merge_radius = static_cast<float> (number ("merge_radius", -1e6, 1e6));
    s.fused.min_mode_confidence = static_cast<float> (number ("min_mode_confidence", -1e6, 1e6));
    s.forest_bytes = static_cast<std::uint64_t> (number ("forest_bytes", 0, 1e12));
    s.forest_stride = static_cast<int> (number ("forest_stride", -1e6, 1e6));
    if (!f.contains ("forest") || !f["forest"].is_string ())
      throw std::invalid_argument (name ("fused.forest") + " is missing or not a file name");
    s.forest_file = f["forest"].get<std::string> ();
    // Models written before the window rescoring name no sliding-window model.
    if (f.contains ("window"))
    {
      if (!f["window"].is_string ())
        throw std::invalid_argument (name ("fused.window") + " is not a file name");
      s.window_file = f["window"].get<std::string> ();
      s.window_weight = static_cast<float> (number ("window_weight", -1e6, 1e6));
    }
  }
  s.validate (name);
  return s;
}

DetectorModel::DetectorModel (std::shared_ptr<const PatchClassifier> classifier, const DetectorSettings &settings)
  : classifier_ (std::move (classifier)), settings_ (settings)
{
  if (!classifier_ || !classifier_->trained ())
    throw std::invalid_argument ("a detector model needs a trained classifier");
  settings_.validate ([] (const std::string &key) { return key; });
  checkGeometry (classifier_->patchGeometry (), "the classifier");
}

DetectorModel
DetectorModel::load (const std::string &path)
{
  auto classifier = std::make_shared<PatchClassifier> (PatchClassifier::load (path));
  const nlohmann::json &metadata = classifier->metadata ();
  DetectorModel model;
  try
  {
    model.settings_ = DetectorSettings::fromJson (metadata, path);
    checkGeometry (classifier->patchGeometry (), path);
  }
  catch (const std::invalid_argument &e)
  {
    throw ModelError (e.what ());
  }
  // Older models kept a copy of the geometry in the metadata: it must agree with the one
  // the classifier was trained with, or the file is not what it claims.
  if (metadata.contains ("patch") && metadata["patch"].is_object ())
  {
    const auto &p = metadata["patch"];
    const PatchGeometry &g = classifier->patchGeometry ();
    const auto differs = [&p] (const char *key, double value) {
      return p.contains (key) && (!p[key].is_number () || p[key].get<float> () != static_cast<float> (value));
    };
    if (differs ("size", g.size) || differs ("extent", g.extent) || differs ("clamp", g.clamp))
      throw ModelError (path + ": the settings' patch geometry differs from the classifier's");
  }
  if (metadata.contains ("training") && metadata["training"].is_object ())
    model.training_ = metadata["training"];
  if (model.settings_.kind == DetectorKind::Fused)
  {
    const std::filesystem::path forest (model.settings_.forest_file);
    model.forest_path_ =
        (forest.is_absolute () ? forest : std::filesystem::path (path).parent_path () / forest).lexically_normal ().string ();
    if (!model.settings_.window_file.empty ())
    {
      const std::filesystem::path window (model.settings_.window_file);
      model.window_path_ = (window.is_absolute () ? window : std::filesystem::path (path).parent_path () / window)
                               .lexically_normal ()
                               .string ();
    }
    if (classifier->auxiliaryNames () != fusedFeatureNames ())
      throw ModelError (path + ": a fused model whose classifier does not take this build's forest features");
  }
  model.classifier_ = classifier;
  return model;
}

void
DetectorModel::save (const std::string &path, const nlohmann::json &training) const
{
  if (!classifier_)
    throw std::logic_error ("DetectorModel::save: no classifier");
  nlohmann::json metadata = settings_.toJson ();
  metadata["training"] = training;
  classifier_->save (path, metadata);
}

DetectorModel::ConstPtr
loadWindowModel (const std::string &path, const DetectorModel &fused, const std::string &named_by)
{
  const std::string named =
      named_by.empty () ? std::string ()
                        : " (the window model " + named_by + " names: keep it beside it, or give a window weight of 0)";
  DetectorModel::ConstPtr window;
  try
  {
    window = std::make_shared<const DetectorModel> (DetectorModel::load (path));
  }
  catch (const ModelError &e)
  {
    if (named.empty ())
      throw;
    throw ModelError (e.what () + named);
  }
  window->requireKind (DetectorKind::SlidingWindow, path + named);
  if (window->classifier ().classes () != fused.classifier ().classes ())
    throw std::invalid_argument (path + named + " names " + std::to_string (window->classifier ().classes ()) +
                                 " classes, the fused model " + std::to_string (fused.classifier ().classes ()));
  if (!window->classifier ().auxiliaryNames ().empty ())
    throw std::invalid_argument (path + named + ": its classifier takes auxiliary features, which a sliding-window "
                                 "model's never does");
  return window;
}

WindowChoice
chooseWindowModel (const DetectorModel &model, const std::string &model_file, bool run_fused,
                   const std::string &given_path, float given_weight, float default_weight,
                   const std::string &path_option, const std::string &weight_option)
{
  if (!given_path.empty () && !run_fused)
    throw std::invalid_argument (path_option + " rescores a fused model's candidates; " + model_file +
                                 " is not run as a fused model");
  WindowChoice choice;
  choice.own = given_path.empty ();
  choice.path = !given_path.empty () ? given_path : run_fused ? model.windowPath () : std::string ();
  if (choice.path.empty () && given_weight > 0.f)
    throw std::invalid_argument (weight_option + " needs a window model: " + model_file +
                                 (run_fused ? " names none (give " + path_option + ")" : " is not run as a fused model"));
  choice.weight = given_weight >= 0.f              ? given_weight
                  : choice.own && !choice.path.empty () ? model.settings ().window_weight
                                                        : default_weight;
  if (!(choice.weight > 0.f))
    choice.path.clear ();
  return choice;
}

void
DetectorModel::requireKind (DetectorKind expected, const std::string &path) const
{
  auto described = [] (DetectorKind kind) {
    return std::string (kind == DetectorKind::Agex    ? "an AGEX model"
                        : kind == DetectorKind::Fused ? "a fused model"
                                                      : "a sliding-window model");
  };
  if (settings_.kind != expected)
    throw std::invalid_argument (path + " is " + described (settings_.kind) + ", but " + described (expected) +
                                 " is needed here" +
                                 (expected == DetectorKind::Agex    ? " (train one with agex_train without --sliding-window)"
                                  : expected == DetectorKind::Fused ? " (train one with agex_train --fused)"
                                                                    : " (train one with agex_train --sliding-window)"));
}
}  // namespace agex
