#pragma once
// Depth-patch classifier: fragment features (FragmentDictionary) and one-vs-rest
// GentleBoost decision stumps per class (cv::ml::Boost), saved to and loaded from one
// model file. See doc/classifier.md.

#include <agex/classification/fragment_dictionary.h>
#include <agex/classification/model_error.h>
#include <agex/common/point_types.h>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/ml.hpp>

#include <functional>
#include <string>
#include <vector>

namespace agex
{
struct PatchClassifierParams
{
  FragmentDictionaryParams dictionary;
  int weak_count = 150;            ///< GentleBoost rounds per class (decision stumps: max depth 1)
  double weight_trim_rate = 0.95;  ///< cv::ml::Boost weight trimming; 0 or 1: none
  /** Soft cascade (PatchClassifier::classifyCascade): the rounds after which a patch may be
    * rejected (those below weak_count are kept; none: no cascade) ... */
  std::vector<int> cascade_stage_ends = {4, 8, 16, 32, 64, 128};
  /** ... and the minimum confidences its rejection thresholds are fitted for (each in (0, 1),
    * increasing; empty: no cascade). */
  std::vector<float> cascade_levels = {0.02f, 0.05f, 0.1f, 0.2f};
  /** ... and the fractions of those positives it may reject (each in [0, 0.5], increasing;
    * 0: direct backward pruning, none). */
  std::vector<float> cascade_miss_rates = {0.f, 0.01f, 0.02f, 0.05f};
};

/** \brief A soft cascade over a classifier's boosted stumps, fitted by direct backward
  * pruning (Zhang & Viola, NIPS 2007) on the training positives.
  *
  * The stumps of all classes are summed round by round (round r: stump r of every class).
  * After round stage_ends[s] a patch is rejected when for every class c its partial margin
  * is below threshold (m, l, c, s). With miss rate m = 0 that is the smallest partial margin
  * there of the class's training positives whose final confidence reaches level l: no such
  * training positive is ever rejected. With m > 0 each stage may reject the lowest m / stages
  * of them (Bourdev & Brandt's rejection distribution, spread evenly), so that at most the
  * fraction m of them is lost in all and the thresholds no longer hang on a few positives
  * that start badly. */
struct SoftCascade
{
  std::vector<int> stage_ends;    ///< rounds, increasing, each at least 1
  std::vector<float> levels;      ///< minimum confidences, increasing, in (0, 1)
  std::vector<float> miss_rates;  ///< fractions of those positives rejected, increasing, in [0, 0.5]
  std::vector<float> thresholds;  ///< [miss rate][level][class][stage], partial margins (-1e30: never below)
  int classes = 0;

  bool empty () const { return levels.empty () || stage_ends.empty () || miss_rates.empty (); }
  float threshold (std::size_t rate, std::size_t level, std::size_t cls, std::size_t stage) const
  {
    return thresholds[((rate * levels.size () + level) * static_cast<std::size_t> (classes) + cls) *
                          stage_ends.size () +
                      stage];
  }
  /** The largest level at most min_confidence, or -1 (no cascade at that confidence). */
  int levelFor (float min_confidence) const;
  /** The largest miss rate at most max_miss_rate, or -1. */
  int rateFor (float max_miss_rate) const;
};

/** The patch geometry a model was trained on; a detector must cut its patches the same way
  * (agex::DepthPatchEstimation's setPatchSize, setPatchExtent, setClampDepth). */
struct PatchGeometry
{
  int size = 0;         ///< cells per side
  float extent = 0.f;   ///< metres across (size * metres_per_cell of the training patches)
  float clamp = 0.f;    ///< relative depth clamp and background value, metres
};

/** The deepest nesting a model file may have, as bounded by yamlNestingBound (agex's own
  * models stay below 100; OpenCV's YAML parser overflows an 8 MB stack at some tens of
  * thousands of levels). */
constexpr std::size_t kMaxModelNesting = 1000;
/** The largest model file read (agex's own are a few MB). */
constexpr std::size_t kMaxModelFileBytes = std::size_t (256) << 20;

/** \brief An upper bound on how deep cv::FileStorage's YAML parser nests (and recurses) on
  * yaml, found in one linear pass without parsing. Flow collections: every '[' and '{'
  * counts, and the count drops to 0 only at a line that no open flow collection may continue
  * (OpenCV requires continuation lines to be indented past the block item holding the
  * collection). Block collections: at most one per column of the line's indentation, plus
  * one per ':' or '-' on the line. Quotes are ignored, so text in strings only ever raises
  * the bound. Scanning stops once the bound exceeds limit.
  * \param line if not null, the 1-based line where the returned bound was reached */
std::size_t yamlNestingBound (const std::string &yaml, std::size_t limit = static_cast<std::size_t> (-1),
                              std::size_t *line = nullptr);

/** \brief Classifies depth patches into classes 0..classes()-1 (or none of them).
  *
  * Training cuts a FragmentDictionary from each class's positives, computes every
  * fragment feature of every training patch once, then trains one binary GentleBoost
  * (cv::ml::Boost::GENTLE, decision stumps) per class: that class against everything else
  * (the other classes and the background, label -1).
  *
  * classify () evaluates only the fragments the stumps use and walks the stumps itself
  * (the same arithmetic as cv::ml::Boost::predict with RAW_OUTPUT | PREDICT_SUM, bit for
  * bit). It is const and thread-safe.
  */
class PatchClassifier
{
public:
  /** Version 2 adds auxiliary features; files without them are still written as version 1,
    * and both are read. */
  static constexpr int kFormatVersion = 2;
  /** The value of the model file's "format" field. */
  static constexpr const char *kFormatName = "agex-model";

  /** \brief Trains the classifier (replacing any previous state; metadata is cleared).
    * \param labels     labels[i] in {-1 (background), 0..classes-1}
    * \param progress   progress (done, total) after each class's booster (may be null)
    * \throws std::invalid_argument on bad input: no patches, patches.size () !=
    *         labels.size (), classes < 1, a label out of range, a class without positives
    *         or without negatives, patches of different sizes or cell pitches, a non-finite
    *         cell, bad parameters (weak_count < 1, weight_trim_rate outside [0, 1], see
    *         FragmentDictionary::build)
    * \throws std::runtime_error if cv::ml::Boost fails to train */
  void train (const std::vector<agex::DepthPatch> &patches, const std::vector<int> &labels, int classes,
              const PatchClassifierParams &params, const std::function<void (int, int)> &progress = nullptr);

  /** \brief train () with auxiliary features: auxiliary[i] (auxiliary_names.size () values,
    * all finite) are appended to patch i's fragment features, so the stumps may split on
    * facts the patch does not show (e.g. a body-part forest's probabilities around the point).
    * classify () must then be given the same features in the same order.
    * \throws std::invalid_argument also if auxiliary does not hold one row per patch of
    *         auxiliary_names.size () finite values, or there are more than 1024 of them */
  void train (const std::vector<agex::DepthPatch> &patches, const std::vector<std::vector<float>> &auxiliary,
              const std::vector<std::string> &auxiliary_names, const std::vector<int> &labels, int classes,
              const PatchClassifierParams &params, const std::function<void (int, int)> &progress = nullptr);

  /** Names of the auxiliary features, in order (empty for a patch-only classifier). */
  const std::vector<std::string> &auxiliaryNames () const { return auxiliary_names_; }

  bool trained () const { return !trees_.empty (); }
  int classes () const { return static_cast<int> (trees_.size ()); }

  /** \brief Per class c: margins[c] = the boosted margin (sum of the weak learners, what
    * cv::ml::Boost::predict returns with RAW_OUTPUT | PREDICT_SUM) and confidences[c] =
    * 1 / (1 + exp (-2 margin)) in [0, 1] (GentleBoost's margin estimates half the
    * log-odds). Either pointer may be null; each must hold classes () values.
    * \throws std::logic_error if not trained, std::invalid_argument if patch.size is not
    *         the trained patch size */
  void classify (const agex::DepthPatch &patch, float *margins, float *confidences) const;
  /** classify () of a classifier trained with auxiliary features: auxiliary holds
    * auxiliaryNames ().size () values (may be null when there are none).
    * \throws std::invalid_argument if auxiliary is null but features are needed */
  void classify (const agex::DepthPatch &patch, const float *auxiliary, float *margins, float *confidences) const;
  /** \brief classify () through the soft cascade (SoftCascade) fitted for the largest level
    * at most min_confidence and the largest miss rate at most max_miss_rate: false if the patch was rejected early (margins and confidences
    * then hold the partial margins where it stopped; a caller drops the patch). A patch not
    * rejected gets exactly classify ()'s values, and is the only one whose features are all
    * computed. Without a cascade (an older model, min_confidence below every level, trees
    * deeper than stumps) this is classify () and returns true.
    * \throws std::invalid_argument as classify (), or for a max_miss_rate below 0 or NaN
    * auxiliary may be null only for a patch-only classifier. */
  bool classifyCascade (const agex::DepthPatch &patch, const float *auxiliary, float min_confidence, float *margins,
                        float *confidences, float max_miss_rate = 0.f) const;
  /** \brief Fits (replaces) the soft cascade of the trained boosters to these examples: the
    * training set, or one made the same way (e.g. for a model trained before the cascade).
    * Only the positives count; stage_ends, levels and miss_rates as PatchClassifierParams's. The boosters
    * and every margin stay as they are.
    * \throws std::logic_error if not trained; std::invalid_argument for examples or
    *         parameters train () would refuse, or patches of another size */
  void fitCascade (const std::vector<agex::DepthPatch> &patches, const std::vector<std::vector<float>> &auxiliary,
                   const std::vector<int> &labels, const std::vector<int> &stage_ends, const std::vector<float> &levels,
                   const std::vector<float> &miss_rates);
  /** The soft cascade (empty for models trained before it, or without one). */
  const SoftCascade &cascade () const { return cascade_; }

  /** \brief Writes the model (format name, version, patch geometry, training parameters,
    * metadata, dictionary, boosters) to path atomically (agex::writeFileAtomic).
    * \throws std::logic_error if not trained, std::runtime_error naming the path if it
    *         cannot be written */
  void save (const std::string &path, const nlohmann::json &metadata) const;
  /** \brief Reads a model written by save (). Before OpenCV's YAML parser sees the bytes,
    * they must be a regular file of at most kMaxModelFileBytes whose nesting is within
    * kMaxModelNesting (yamlNestingBound): that parser recurses once per level and overflows
    * the stack on a file nested some tens of thousands deep.
    * \throws ModelError naming the file and the problem: missing or unreadable, not a regular
    *         file, too large or too deeply nested, not an
    *         agex model, another format version, or damaged (truncated, missing or invalid
    *         nodes, a booster that fails to load or does not fit the dictionary, a fragment
    *         of the wrong size, metadata that is not JSON) */
  static PatchClassifier load (const std::string &path);

  /** The metadata the model was saved with (null after train ()). */
  const nlohmann::json &metadata () const { return metadata_; }

  /** The geometry of the training patches. size and extent come from the patches
    * (size, size * metres_per_cell); clamp is inferred as the largest |cell| of the
    * training patches (the background value +clamp is in almost every real patch): set
    * it with setPatchGeometry when it is known. */
  const PatchGeometry &patchGeometry () const { return geometry_; }
  /** \throws std::invalid_argument if geometry.size is not the trained patch size or
    *         extent / clamp are not finite and positive */
  void setPatchGeometry (const PatchGeometry &geometry);

  const PatchClassifierParams &params () const { return params_; }
  const FragmentDictionary &dictionary () const { return dictionary_; }
  /** The boosters, one per class (cv::ml::Boost::predict on the full feature row gives the
    * same margins as classify). */
  const std::vector<cv::Ptr<cv::ml::Boost>> &boosters () const { return boosters_; }
  /** Sorted indices of the fragments some stump uses: all classify () computes. */
  const std::vector<int> &usedFragments () const { return used_fragments_; }

private:
  /** A tree flattened for evaluation: feature < 0 marks a leaf. */
  struct TreeNode
  {
    int feature = -1;
    float threshold = 0.f;  ///< go left if feature value <= threshold (cv::ml's rule)
    int left = -1, right = -1;
    double value = 0.0;
  };
  /** A depth-1 tree: value <= threshold ? left : right. */
  struct Stump
  {
    int feature = 0;
    float threshold = 0.f;
    double left = 0.0, right = 0.0;
  };
  struct ClassTrees
  {
    std::vector<int> roots;
    std::vector<TreeNode> nodes;
    /** The same trees, in order, when every one is a stump (the usual case): summed
      * without branches. Empty otherwise. */
    std::vector<Stump> stumps;
  };

  /** Validates the boosters against the dictionary and flattens them; fills trees_ and
    * used_fragments_. \throws ModelError (message without the file name) */
  void prepare ();
  /** Fits cascade_ to the training features (rows of samples) and labels, params_'s stages
    * and levels; leaves it empty when the trees are not all stumps. */
  void fitCascadeToRows (const cv::Mat &samples, const std::vector<int> &labels);
  /** Per cascade stage (and one more for the rest): the fragments first used there. Fills
    * stage_fragments_ from cascade_; \throws ModelError if the cascade does not fit. */
  void prepareCascade ();
  /** The features classify () computes without the cascade: all used ones. */
  void computeAllFeatures (const agex::DepthPatch &patch, const float *auxiliary, float *features) const;
  void checkClassifyInput (const agex::DepthPatch &patch, const float *auxiliary, const char *caller) const;

  FragmentDictionary dictionary_;
  std::vector<cv::Ptr<cv::ml::Boost>> boosters_;
  std::vector<ClassTrees> trees_;
  std::vector<int> used_fragments_;
  SoftCascade cascade_;
  std::vector<std::vector<int>> stage_fragments_;
  std::vector<std::string> auxiliary_names_;
  PatchGeometry geometry_;
  PatchClassifierParams params_;
  nlohmann::json metadata_;
};
}  // namespace agex
