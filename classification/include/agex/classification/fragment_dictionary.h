#pragma once
// A dictionary of depth-patch fragments (Torralba, Murphy & Freeman, "Sharing visual
// features for multiclass and multiview object detection", PAMI 2007): small pieces cut
// at random from the positive training patches of each class. The feature of fragment f
// on a patch is the best normalised cross-correlation of f with the patch over a small
// window of positions around where f was cut. See doc/classifier.md.

#include <agex/classification/model_error.h>
#include <agex/common/point_types.h>

#include <opencv2/core/persistence.hpp>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace agex
{
struct FragmentDictionaryParams
{
  int fragments_per_class = 80;     ///< cut from each class's positive patches
  int min_size = 5, max_size = 13;  ///< fragment side in cells (any integer; clipped to the patch size)
  int window_radius = 3;            ///< cells the fragment may shift around its origin
  std::uint64_t seed = 1;           ///< the random cuts are a function of this seed only
};

/** One fragment: a size x size piece of a class's positive patch. */
struct Fragment
{
  int cls = 0;              ///< the class whose positive patch it was cut from
  int x = 0, y = 0;         ///< top-left cell (column, row) in the patch it was cut from
  int size = 0;             ///< side in cells
  int window_radius = 0;    ///< the feature searches x - w..x + w, y - w..y + w
  /** size * size values, row-major, zero-mean and unit-norm (so that a dot product with a
    * zero-mean, unit-norm piece of a patch is their normalised cross-correlation). All
    * zero for a fragment that stayed flat after every try (its feature is always 0). */
  std::vector<float> values;
};

/** \brief Fragment dictionary and its features (Torralba-style shared fragments).
  *
  * Feature f of a patch = max over the positions (px, py) of fragment f's window
  * (px in x - w..x + w, py in y - w..y + w, clipped so the fragment lies inside the patch)
  * of the normalised cross-correlation (Pearson correlation) of the fragment with the
  * patch cells under it. It lies in [-1, 1]: 1 for an exact copy (up to an offset and a
  * positive scale) anywhere in the window, -1 for a negated copy when that is the best
  * the window offers. A flat piece of the patch correlates 0 with every fragment, and an
  * all-zero fragment with every patch.
  *
  * The correlation is computed in 16-bit fixed point (the patch scaled to +-7200 around
  * its mid-range, the unit-norm fragment by up to 32767; see doc/classifier.md) with exact
  * integer sums: it is within about 1e-4 of the real-valued correlation (within 1e-6 for
  * exact copies), "flat" means flat after quantisation, and the features are bit for bit
  * the same on every machine and with every kernel (availableKernels).
  *
  * Thread safety: computeFeatures is const and keeps its scratch space on the stack, so
  * one dictionary may serve many threads.
  */
class FragmentDictionary
{
public:
  /** \brief Cuts params.fragments_per_class fragments from each class's positives.
    *
    * positives[c] = the positive training patches of class c (c = 0..classes-1). Each
    * fragment is a random patch of the class, a random size in min_size..max_size
    * (clipped to the patch size), a random top-left position, all drawn from a
    * std::mt19937_64 seeded with params.seed (the same inputs and seed give the same
    * dictionary on every platform). Flat cuts (zero variance, e.g. all background) are
    * redrawn up to 100 times; a fragment still flat after that is kept all zero.
    * \throws std::invalid_argument for no classes, a class without positives, a null
    *         patch, patches of different or invalid sizes, or bad parameters
    *         (fragments_per_class < 1, min_size < 1, max_size < min_size,
    *         window_radius < 0) */
  void build (const std::vector<std::vector<const agex::DepthPatch *>> &positives,
              const FragmentDictionaryParams &params);

  std::size_t size () const { return fragments_.size (); }
  const std::vector<Fragment> &fragments () const { return fragments_; }
  /** Cells per side of the patches the dictionary was cut from (and works on); 0 if empty. */
  int patchSize () const { return patch_size_; }
  /** The parameters of the last build (or of the dictionary read). */
  const FragmentDictionaryParams &params () const { return params_; }

  /** \brief All features: features[f] for f = 0..size()-1.
    * \throws std::invalid_argument if patch.size != patchSize () */
  void computeFeatures (const agex::DepthPatch &patch, float *features) const;
  /** \brief Only the features listed in which (fragment indices; others are untouched).
    * \throws std::invalid_argument if patch.size != patchSize () or an index is out of range */
  void computeFeatures (const agex::DepthPatch &patch, const std::vector<int> &which, float *features) const;

  /** \brief A patch quantised once (integral images and packed cells) for several
    * computeFeatures calls over it: a soft cascade computes a patch's features stage by
    * stage and stops when it rejects the patch. One per thread; reusable for the next patch. */
  class PreparedPatch
  {
  public:
    PreparedPatch ();
    ~PreparedPatch ();
    PreparedPatch (PreparedPatch &&) noexcept;
    PreparedPatch &operator= (PreparedPatch &&) noexcept;
    /** Cells per side of the patch prepared (0: none yet). */
    int size () const;

  private:
    friend class FragmentDictionary;
    struct Impl;
    std::unique_ptr<Impl> impl_;
  };
  /** \brief Quantises patch into prepared (replacing what it held).
    * \throws std::invalid_argument if patch.size != patchSize () */
  void prepare (const agex::DepthPatch &patch, PreparedPatch &prepared) const;
  /** \brief features[which[i]] for i < count, on a prepared patch; the same values as
    * computeFeatures on the patch. Indices are not checked here (a caller's hot loop):
    * each must be < size ().
    * \throws std::invalid_argument if prepared holds no patch of patchSize () */
  void computeFeatures (const PreparedPatch &prepared, const int *which, std::size_t count, float *features) const;

  /** \brief The feature kernels this build offers on this processor, fastest first:
    * "avx-vnni", "avx2", "sse2" (x86-64 builds with GCC) and "generic" (plain C++, always).
    * They give bitwise identical features; the fastest is used unless selectKernel says
    * otherwise. */
  static std::vector<std::string> availableKernels ();
  /** \brief Selects a kernel for the whole process ("" or "auto": the fastest); false
    * (nothing changed) if it is not available. For tests and timing. */
  static bool selectKernel (const std::string &name);
  /** The kernel in use. */
  static std::string kernelName ();

  /** \brief Writes the dictionary's fields into the current (open) map of fs, OpenCV's
    * Algorithm::write convention: fs << "dictionary" << "{"; dict.write (fs); fs << "}"; */
  void write (cv::FileStorage &fs) const;
  /** \brief Reads a dictionary from the map node write () filled.
    * \throws ModelError describing the damage (missing or invalid fields, a fragment
    *         outside the patch, values of the wrong count or not finite); the dictionary
    *         is left unchanged then */
  void read (const cv::FileNode &node);

  /** Implementation detail: a fragment as the feature kernels use it, values in 16-bit
    * fixed point packed in pairs of neighbouring columns (see fragment_dictionary.cpp). */
  struct Packed
  {
    int size = 0, pairs = 0;              ///< side, pairs per row (size + 1) / 2
    std::vector<std::int32_t> words;      ///< size x pairs: column 2j in the low half, 2j + 1 (or 0) in the high
    double sum = 0.0;                     ///< sum of the fixed-point values
    double norm = 0.0;                    ///< size^2 * sum of squares - sum^2 (0: all-zero fragment)
  };

private:
  void pack ();

  std::vector<Fragment> fragments_;
  std::vector<Packed> packed_;
  int patch_size_ = 0;
  FragmentDictionaryParams params_;
};
}  // namespace agex
