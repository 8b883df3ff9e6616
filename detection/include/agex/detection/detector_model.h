#pragma once
// The detector's model file: the boosted patch classifier, its patch geometry (stored
// once, in the classifier) and the pipeline and detector settings it was trained with, in
// the classifier file's metadata (doc/classifier.md). This file owns that schema.

#include <agex/classification/patch_classifier.h>
#include <agex/detection/depth_pipeline.h>
#include <agex/detection/fused_candidates.h>

#include <nlohmann/json.hpp>

#include <memory>
#include <string>
#include <vector>

namespace agex
{
/** The detector a model was trained for (its patches are cut differently). */
enum class DetectorKind
{
  Agex,           ///< AGEX points, patches oriented along the point's orientation
  SlidingWindow,  ///< every window position, upright patches (agex::SlidingWindowDetector)
  Fused           ///< AGEX points and a forest's part modes, patches and forest features (agex::FusedFeatures)
};
/** "agex", "sliding_window" or "fused", as model files name them. */
const char *detectorKindName (DetectorKind kind);

/** Window layout of a sliding-window model (agex::SlidingWindowDetector). */
struct SlidingWindowParams
{
  /** Pixels between window centres, [1, 64]; -1: stride_metres at the person's depth
    * (agex::SlidingWindowDetector::setStrideMetres). Models written before it: pixels. */
  int stride = -1;
  std::vector<float> scales{1.f};  ///< window extents over the trained extent: 1-16 of them, each in (0, 10]
  float stride_metres = 0.015f;    ///< metres between window centres with stride -1, (0, 0.5]
};

/** Everything a model needs to be applied as it was trained, besides the classifier. */
struct DetectorSettings
{
  DepthPipelineParams pipeline;
  /** Detections of a class closer than this (metres) to a more confident one are dropped. */
  float suppression_radius = 0.15f;
  DetectorKind kind = DetectorKind::Agex;  ///< models without the field are AGEX models
  SlidingWindowParams sliding_window;      ///< used by sliding-window models only
  /** Fused models: the candidates, and the forest the classifier's forest features came
    * from (a path relative to the model file's directory, and its size in bytes, checked). */
  FusedCandidateParams fused;
  std::string forest_file;
  std::uint64_t forest_bytes = 0;
  int forest_stride = 0;  ///< pixel stride of the forest pass, 1-8; 0: by the focal length (agex::forestStrideFor)
  /** Fused models: a sliding-window model whose confidences blend into the candidates'
    * (BodyPartDetector::setWindowRescoring), a path relative to the model file's directory
    * (empty: none), and its weight in [0, 1]. The fused classifier does not depend on it. */
  std::string window_file;
  float window_weight = 0.f;

  /** \throws std::invalid_argument naming the setting (name (key)) out of range */
  void validate (const std::function<std::string (const std::string &key)> &name) const;
  /** The settings as a model's metadata holds them. */
  nlohmann::json toJson () const;
  /** \throws std::invalid_argument naming source and the key of a missing, mistyped or
    *         out-of-range setting */
  static DetectorSettings fromJson (const nlohmann::json &doc, const std::string &source);
};

/** \brief A trained detector: classifier and settings, loaded and saved as one file. */
class DetectorModel
{
public:
  using Ptr = std::shared_ptr<DetectorModel>;
  using ConstPtr = std::shared_ptr<const DetectorModel>;

  DetectorModel () = default;
  /** \throws std::invalid_argument if the classifier is missing or untrained, or a setting
    *         or the patch geometry is out of range */
  DetectorModel (std::shared_ptr<const PatchClassifier> classifier, const DetectorSettings &settings);

  /** \brief Reads a model file.
    * \throws agex::ModelError naming the file and the problem: a damaged classifier, or
    *         missing, malformed or out-of-range settings (the setting named) */
  static DetectorModel load (const std::string &path);
  /** \brief Writes the model atomically; training (commands, counts, times) is kept in the
    * metadata beside the settings. \throws std::runtime_error naming the path */
  void save (const std::string &path, const nlohmann::json &training = nlohmann::json::object ()) const;

  /** \throws std::invalid_argument naming path when the model is not of the kind expected */
  void requireKind (DetectorKind expected, const std::string &path) const;

  bool valid () const { return classifier_ != nullptr; }
  const PatchClassifier &classifier () const { return *classifier_; }
  const std::shared_ptr<const PatchClassifier> &classifierPtr () const { return classifier_; }
  const DetectorSettings &settings () const { return settings_; }
  const PatchGeometry &patchGeometry () const { return classifier_->patchGeometry (); }
  /** A fused model's forest as a path (its settings' forest_file resolved against the model
    * file's directory); empty for other models or a model not loaded from a file. */
  const std::string &forestPath () const { return forest_path_; }
  /** A fused model's sliding-window model as a path (window_file resolved likewise); empty
    * when it names none. */
  const std::string &windowPath () const { return window_path_; }
  /** The metadata's "training" object of a loaded model (empty for a new one). */
  const nlohmann::json &training () const { return training_; }

private:
  std::shared_ptr<const PatchClassifier> classifier_;
  DetectorSettings settings_;
  nlohmann::json training_ = nlohmann::json::object ();
  std::string forest_path_;
  std::string window_path_;
};
/** \brief A fused model's sliding-window model (BodyPartDetector::setWindowRescoring): loads
  * path and checks it is a sliding-window model of fused's classes without auxiliary features.
  * named_by: the fused model file that names it (said in every error), empty when the user gave it.
  * \throws agex::ModelError for a file that cannot be read, std::invalid_argument for a model
  *         that does not fit, both naming path */
DetectorModel::ConstPtr loadWindowModel (const std::string &path, const DetectorModel &fused,
                                         const std::string &named_by = std::string ());

/** The window model a detector runs with, as the apps and the Python module choose it. */
struct WindowChoice
{
  std::string path;    ///< empty: none (or weight 0)
  float weight = 0.f;
  bool own = false;    ///< the model names it (not given by the user)
};
/** \brief The given window model (given_path) or, when none is given, the one model_file's
  * model names if it runs as a fused model (run_fused); the given weight (< 0: not given) or
  * else the model's own weight for its own window, BodyPartDetector's default for a given one.
  * path_option and weight_option name the settings in errors (e.g. "--window-model").
  * \throws std::invalid_argument for a window model given to a model not run as fused, or a
  *         positive weight without any window model */
WindowChoice chooseWindowModel (const DetectorModel &model, const std::string &model_file, bool run_fused,
                                const std::string &given_path, float given_weight, float default_weight,
                                const std::string &path_option, const std::string &weight_option);
}  // namespace agex
