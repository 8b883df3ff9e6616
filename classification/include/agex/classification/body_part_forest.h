#pragma once
// A randomized decision forest over depth-comparison features that labels body parts per
// pixel (Shotton et al., "Real-Time Human Pose Recognition in Parts from Single Depth
// Images", CVPR 2011), evaluated on the CPU exactly as PCL's gpu/people module evaluates
// its published forests (Buys et al. 2014). doc/forest.md lists every PCL fact matched and
// where it is in PCL's source.

#include <agex/classification/model_error.h>

#include <pcl/point_cloud.h>
#include <pcl/types.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

namespace agex
{
/** \brief A depth image as the forest reads it: PCL people's convention (doc/forest.md).
  *
  * Pixels are uint16 millimetres; kNoData (0) is a foreground pixel without a measurement and
  * kBackground (65535) anything that is not the person (PCL's prepareForeGroundDepth), so that
  * a probe that leaves the person reads "very far". Reads clamp to the image (PCL's texture
  * address mode). The image may hold only a window of its frame: everything outside the
  * window must be background, and then clamping to the window reads the same values as
  * clamping to the frame (a window border is background or the frame's edge), so build()
  * keeps a one-pixel background margin around the foreground. */
class ForestDepthImage
{
public:
  static constexpr std::uint16_t kNoData = 0;
  static constexpr std::uint16_t kBackground = 65535;

  /** \brief A frame_width x frame_height frame of which the window (x0, y0, width, height)
    * is stored, all background. An empty or out-of-frame window is clipped. */
  void reset (int frame_width, int frame_height, int x0, int y0, int width, int height);

  /** \brief Builds the image of an organized cloud for the foreground pixels given (row-major
    * indices; out-of-range ones are ignored): their depth (kNoData where not finite), and
    * every other pixel background except, when dilation > 0, the pixels within dilation
    * pixels of a foreground pixel (a (2 dilation + 1)^2 square, PCL's 5x5 mask dilation
    * for dilation 2), which keep their own depth as in PCL's dilated person mask. */
  template <typename PointT>
  void build (const pcl::PointCloud<PointT> &cloud, const pcl::Indices &foreground, int dilation = 0);

  /** \brief PCL people's millimetres of a point: static_cast<uint16>(z * 1000) for a finite
    * point (PeopleDetector::process), kNoData when not finite or outside [1, 65535) mm. */
  static std::uint16_t toMillimetres (float x, float y, float z)
  {
    if (!std::isfinite (x) || !std::isfinite (y) || !std::isfinite (z))
      return kNoData;
    const float mm = z * 1000.f;
    if (!(mm >= 1.f) || !(mm < 65535.f))
      return kNoData;
    return static_cast<std::uint16_t> (mm);
  }

  int frameWidth () const { return frame_width_; }
  int frameHeight () const { return frame_height_; }
  int x0 () const { return x0_; }
  int y0 () const { return y0_; }
  int width () const { return width_; }
  int height () const { return height_; }
  bool empty () const { return width_ <= 0 || height_ <= 0; }
  /** True if frame pixel (u, v) lies inside the stored window. */
  bool contains (int u, int v) const { return u >= x0_ && v >= y0_ && u < x0_ + width_ && v < y0_ + height_; }

  /** Depth at frame pixel (u, v), clamped to the window (background when empty). */
  std::uint16_t at (int u, int v) const
  {
    if (empty ())
      return kBackground;
    int x = u - x0_, y = v - y0_;
    x = x < 0 ? 0 : (x >= width_ ? width_ - 1 : x);
    y = y < 0 ? 0 : (y >= height_ ? height_ - 1 : y);
    return data_[static_cast<std::size_t> (y) * width_ + x];
  }
  /** Sets frame pixel (u, v); ignored outside the window. */
  void set (int u, int v, std::uint16_t mm)
  {
    if (contains (u, v))
      data_[static_cast<std::size_t> (v - y0_) * width_ + (u - x0_)] = mm;
  }
  const std::uint16_t *data () const { return data_.data (); }

private:
  int frame_width_ = 0, frame_height_ = 0;
  int x0_ = 0, y0_ = 0, width_ = 0, height_ = 0;
  std::vector<std::uint16_t> data_;
};

/** \brief A forest of binary decision trees over depth-comparison features
  *   f(x) = d(x + u s) - d(x + v s),  s = F / d(x),
  * d in millimetres, u and v integer offsets and F = 1000 (PCL's trees::focal), so that an
  * offset is in pixel·metres: the same body distance at any depth. Offsets are those of the
  * model's reference focal length (PCL's: the Kinect's 525 px); on a camera with focal
  * length fx, fy the scale becomes s = (1000 fx / f_ref) / d(x) horizontally and
  * (1000 fy / f_ref) / d(x) vertically. A node sends a pixel right when f(x) > threshold.
  *
  * Leaves hold a class distribution (forests trained here) or a single class (PCL's trees).
  * The model keeps its class set: each class has a name and the body part (LabelPart) it
  * counts for, or -1 for none (e.g. PCL's Background).
  *
  * Trees are stored compactly: 12-byte nodes (four int16 offsets and a float threshold);
  * PCL's complete trees in PCL's implicit layout (children of node n at 2n+1, 2n+2, leaves
  * after 2^depth - 1 nodes), trained trees in a sparse layout with one child index per node.
  *
  * evaluate() is const and thread-safe: one forest may serve any number of threads. */
class BodyPartForest
{
public:
  using Ptr = std::shared_ptr<BodyPartForest>;
  using ConstPtr = std::shared_ptr<const BodyPartForest>;

  /** Deepest tree read or trained: 24 levels (PCL's published trees have 20). */
  static constexpr int kMaxDepth = 24;
  static constexpr int kMaxTrees = 64;
  static constexpr int kMaxClasses = 255;
  /** Test nodes of all of a PCL forest's trees together (400 MB at 12 bytes): two depth-24
    * trees, 32 of depth 20. A 9 KB .bz2 holds a depth-24 tree, so file sizes bound nothing. */
  static constexpr std::uint64_t kMaxForestNodes = std::uint64_t (1) << 25;
  /** Text decompressed from all of a forest's PCL tree files together (1 GiB). */
  static constexpr std::uint64_t kMaxForestTextBytes = std::uint64_t (1) << 30;
  /** How deep below a forest directory tree files are looked for, and how many entries. */
  static constexpr int kMaxSearchDepth = 16;
  static constexpr std::size_t kMaxSearchEntries = 100000;
  /** PCL's trees::focal (tree.h): the constant of s = F / d. */
  static constexpr float kFeatureScale = 1000.f;
  /** The focal length PCL's trees were trained for (label_common.h FOCAL, the Kinect's). */
  static constexpr float kPclFocalLength = 525.f;
  /** The reference focal lengths a forest may have, pixels. Depth cameras have about 100 to a
    * few thousand; evaluate () refuses a camera more than 50 times the reference, so a forest
    * made for 1 px would load and then refuse every frame. */
  static constexpr float kMinReferenceFocal = 10.f;
  static constexpr float kMaxReferenceFocal = 1e5f;
  /** PCL's label for pixels at kBackground (multi_tree.cu, KernelCUDA_MultiTreePass). */
  static constexpr int kPclBackgroundLabel = 29;
  /** PCL's NUM_LABELS (tree.h): labels of a PCL forest are 0..31. */
  static constexpr int kPclLabelCount = 32;

  struct Node
  {
    std::int16_t du1 = 0, dv1 = 0, du2 = 0, dv2 = 0;
    float threshold = 0.f;
  };

  struct Tree
  {
    int depth = 0;          ///< levels of tests on the longest path
    bool complete = false;  ///< PCL's layout (see above)
    /** complete: the 2^depth - 1 internal nodes; sparse: one per node slot (root at 0). */
    std::vector<Node> nodes;
    /** Sparse only, one per slot: the left child's slot (the right child's is the next), or
      * -(leaf + 1) for a leaf. Children always come after their parent. */
    std::vector<std::int32_t> children;
    /** Per leaf: its class (PCL: the leaf's label; trained: the distribution's argmax). */
    std::vector<std::uint8_t> leaf_labels;
    /** Per leaf, numClasses () probabilities; empty: each leaf is its leaf_labels class. */
    std::vector<float> leaf_distributions;

    std::size_t leafCount () const { return leaf_labels.size (); }
  };

  struct ClassInfo
  {
    std::string name;
    int part = -1;  ///< LabelPart it counts for, -1: none
  };

  /** How the trees' outputs are combined into the pixel's class. */
  enum class VoteRule
  {
    /** Shotton et al.: the mean of the trees' leaf distributions; its argmax wins (the lowest
      * class on a tie). */
    Average,
    /** PCL (multi_tree.cu KernelCUDA_MultiTreeMerge): each tree votes its leaf's class; the
      * most voted wins; on a tie for the maximum the 3x3 neighbourhood's votes (of pixels
      * less than 50 mm away in depth, the pixel itself counted again) are added and the
      * most voted wins, the lowest label on a tie. Probabilities are the vote fractions. */
    PclMajority
  };

  /** What pixels skipped by a stride get. */
  enum class StrideFill
  {
    Copy,       ///< the result of the evaluated pixel of their stride cell
    Unlabelled  ///< nothing: label -1
  };

  struct EvaluationOptions
  {
    /** Focal lengths of the camera (pixels); 0 means the forest's reference focal length. */
    float fx = 0.f, fy = 0.f;
    /** \brief Evaluate one pixel per stride x stride cell of the frame (cells at multiples of
      * stride): the cell's first foreground pixel in row-major order. The others take its
      * result (StrideFill::Copy) or stay unlabelled. 1 evaluates every pixel. */
    int stride = 1;
    StrideFill fill = StrideFill::Copy;
    /** \brief PCL's label smoothing after the vote (smooth.cu, smoothLabelImage with patch 5
      * and 300 mm, as RDFBodyPartsDetector::process runs it): a pixel takes the most frequent
      * label of the body-part classes among the 5x5 pixels within 300 mm in depth, the lowest
      * on a tie, its own if there are none; pixels within 2 of the frame's edge keep theirs.
      * Changes labels only, not probabilities. Evaluates the whole foreground of the image
      * (the dilated ring too) since the neighbours' labels are needed. */
    bool pcl_smoothing = false;
    /** Threads to split the pixels over (results do not depend on it). */
    int threads = 1;
    /** Use the portable descent even where the FMA kernel could run (for tests: both give
      * the same leaves). */
    bool generic_kernel = false;
    /** Output the probabilities of the parts (head, hand, foot, other body: the sums of
      * their classes' probabilities) instead of the classes': less to write for a forest of
      * many classes such as PCL's 32. */
    bool part_probabilities = false;
  };

  /** One evaluation: row i belongs to pixels[i] of the call. */
  struct Evaluation
  {
    /** Columns of probabilities: numClasses (), or kLabelPartCount if per_part. */
    int num_classes = 0;
    bool per_part = false;  ///< EvaluationOptions::part_probabilities
    /** pixels.size () x num_classes: the pixel's class (or part) distribution (0 where
      * unlabelled). */
    std::vector<float> probabilities;
    /** The winning class of each pixel, -1 where it is not labelled (not foreground, no
      * depth, outside the image, or skipped by the stride with StrideFill::Unlabelled). */
    std::vector<int> labels;
    /** Pixels the trees were run on (stride representatives, ring and tie-break extras). */
    std::size_t evaluated = 0;
  };

  BodyPartForest () = default;

  /** \brief A forest from its parts.
    * \throws ModelError if they are inconsistent (see the file checks in doc/forest.md) */
  BodyPartForest (std::vector<ClassInfo> classes, std::vector<Tree> trees, float reference_focal,
                  VoteRule rule, int background_class);

  /** \brief Loads a forest: one of our model files, a PCL tree file (text, or text
    * compressed with bzip2 when the name ends in .bz2), or a directory, whose PCL tree files
    * (names ending in .txt or .txt.bz2) are found recursively and loaded in sorted path
    * order as one forest.
    * \throws ModelError naming the file (and line) of any problem */
  static Ptr load (const std::string &path);

  /** \brief PCL tree files as one forest with PCL's 32 labels (label_common.h), mapped to
    * parts: FaceLB/RB/LT/RT -> head, Lhand/Rhand -> hand, Lfoot/Rfoot -> foot, the other
    * body labels (0-26) -> other body, Groundplane, Ceiling, Background, Plane, NOLABEL ->
    * none; vote rule PclMajority, reference focal 525, background class 29. The trees' declared
    * depths are read first: a forest of more than kMaxForestNodes nodes is refused before any
    * tree is read, and one of more than kMaxForestTextBytes of text while it is read.
    * \throws ModelError naming the file and line */
  static Ptr loadPclTrees (const std::vector<std::string> &files);
  /** The PCL tree files under a directory, recursively (at most kMaxSearchDepth levels
    * below it, kMaxSearchEntries entries), in sorted path order.
    * \throws ModelError if it is not a readable directory, holds none, or is deeper or larger */
  static std::vector<std::string> findPclTreeFiles (const std::string &directory);
  /** \brief Parses one PCL tree in PCL's text format (trees.cpp loadTree: the depth D on the
    * first line, then 2^D - 1 lines "du1 dv1 du2 dv2 threshold", then 2^D lines of one leaf
    * label), one item per line, every value in range (offsets and thresholds int16, labels
    * 0-31, 1 <= D <= kMaxDepth), at most kMaxForestNodes nodes and kMaxForestTextBytes of text.
    * \throws ModelError "name:line: problem" on malformed or truncated text */
  static Tree readPclTree (std::istream &text, const std::string &name);
  /** PCL's 32 labels as classes (names of label_common.h part_t, parts as above). */
  static std::vector<ClassInfo> pclClasses ();

  /** \brief Writes the forest as our binary model file (doc/forest.md), atomically.
    * metadata is stored as is (e.g. JSON with the training parameters).
    * \throws std::runtime_error naming the path on failure */
  void save (const std::string &path, const std::string &metadata = std::string ()) const;
  /** The model file's bytes. */
  std::string serialize (const std::string &metadata = std::string ()) const;
  /** \brief Parses our binary model file's bytes; name is used in messages.
    * \throws ModelError naming it: not a forest, another version, truncated, damaged */
  static Ptr deserialize (const std::string &bytes, const std::string &name);

  bool empty () const { return trees_.empty (); }
  int numClasses () const { return static_cast<int> (classes_.size ()); }
  const std::vector<ClassInfo> &classes () const { return classes_; }
  /** The part class c counts for (-1: none, also for c out of range). */
  int classPart (int c) const { return c >= 0 && c < numClasses () ? classes_[c].part : -1; }
  const std::vector<Tree> &trees () const { return trees_; }
  float referenceFocalLength () const { return reference_focal_; }
  VoteRule voteRule () const { return rule_; }
  void setVoteRule (VoteRule rule) { rule_ = rule; }
  /** The class of background pixels (kBackground) in the PclMajority tie-break; -1: none. */
  int backgroundClass () const { return background_class_; }
  /** The metadata string of the file it was loaded from (empty otherwise). */
  const std::string &metadata () const { return metadata_; }
  /** Bytes of node and leaf storage. */
  std::size_t memoryBytes () const;

  /** \brief Labels the given pixels (row-major frame indices) of a depth image.
    * Pixels whose depth is kNoData or kBackground, or outside the frame, are not labelled.
    * \return false (with PCL_ERROR) on misuse: an empty forest, stride < 1, a focal length
    *         that is not finite and positive or scales offsets more than 50 times */
  bool evaluate (const ForestDepthImage &depth, const pcl::Indices &pixels, const EvaluationOptions &options,
                 Evaluation &output) const;

  /** The leaf that pixel (u, v) reaches in tree t (its depth must be a measurement), with
    * feature scales su = (1000 fx / f_ref) / d, sv likewise (see scales ()). */
  int leafOf (int t, const ForestDepthImage &depth, int u, int v, float su, float sv) const;
  /** The feature scales of depth mm (> 0) for the scale factors F_u, F_v (see above). */
  static void scales (float Fu, float Fv, std::uint16_t mm, float &su, float &sv)
  {
    su = Fu / static_cast<float> (mm);
    sv = Fv / static_cast<float> (mm);
  }

private:
  std::vector<ClassInfo> classes_;
  std::vector<Tree> trees_;
  float reference_focal_ = kPclFocalLength;
  VoteRule rule_ = VoteRule::Average;
  int background_class_ = -1;
  std::string metadata_;

  void check () const;
};

/** \brief The feature f = d(x + u1 s) - d(x + u2 s) of pixel (u, v) with scales (su, sv),
  * exactly as PCL's GPU kernel computes it (doc/forest.md): probe coordinates in float as
  * one fused multiply-add (u + du * su rounded once), texel = floor, clamped. Inline so that
  * training and evaluation share it bit for bit. */
inline int
forestFeature (const ForestDepthImage &depth, int u, int v, float su, float sv, const BodyPartForest::Node &node)
{
  // float (double (a) * b + c) is the fused float multiply-add: the double result is exact
  // (an int16 times a float plus a small int fits 53 bits), so it is rounded once.
  // Truncation then clamping equals floor then clamping (PCL's CPU fetcher truncates).
  const float x1 = static_cast<float> (static_cast<double> (node.du1) * su + u);
  const float y1 = static_cast<float> (static_cast<double> (node.dv1) * sv + v);
  const float x2 = static_cast<float> (static_cast<double> (node.du2) * su + u);
  const float y2 = static_cast<float> (static_cast<double> (node.dv2) * sv + v);
  const int d1 = depth.at (static_cast<int> (x1), static_cast<int> (y1));
  const int d2 = depth.at (static_cast<int> (x2), static_cast<int> (y2));
  return d1 - d2;
}

template <typename PointT>
void
ForestDepthImage::build (const pcl::PointCloud<PointT> &cloud, const pcl::Indices &foreground, int dilation)
{
  const int w = static_cast<int> (cloud.width), h = static_cast<int> (cloud.height);
  const long long n = static_cast<long long> (w) * h;
  if (dilation < 0)
    dilation = 0;
  int u0 = w, v0 = h, u1 = -1, v1 = -1;
  for (const auto i : foreground)
    if (i >= 0 && i < n && cloud.size () == static_cast<std::size_t> (n))
    {
      const int u = static_cast<int> (i % w), v = static_cast<int> (i / w);
      u0 = std::min (u0, u), v0 = std::min (v0, v), u1 = std::max (u1, u), v1 = std::max (v1, v);
    }
  if (u1 < 0)
  {
    reset (w, h, 0, 0, 0, 0);
    return;
  }
  const int margin = dilation + 1;
  reset (w, h, u0 - margin, v0 - margin, u1 - u0 + 1 + 2 * margin, v1 - v0 + 1 + 2 * margin);
  std::vector<std::uint8_t> given (data_.size (), 0);
  for (const auto i : foreground)
  {
    if (i < 0 || i >= n)
      continue;
    const int u = static_cast<int> (i % w), v = static_cast<int> (i / w);
    const auto &p = cloud[static_cast<std::size_t> (i)];
    set (u, v, toMillimetres (p.x, p.y, p.z));
    given[static_cast<std::size_t> (v - y0_) * width_ + (u - x0_)] = 1;
  }
  if (dilation == 0)
    return;
  for (int y = 0; y < height_; ++y)
    for (int x = 0; x < width_; ++x)
    {
      if (given[static_cast<std::size_t> (y) * width_ + x] != 1)
        continue;  // dilate the foreground only, not the ring
      for (int dy = -dilation; dy <= dilation; ++dy)
        for (int dx = -dilation; dx <= dilation; ++dx)
        {
          const int xx = x + dx, yy = y + dy;
          if (xx < 0 || yy < 0 || xx >= width_ || yy >= height_)
            continue;
          const std::size_t k = static_cast<std::size_t> (yy) * width_ + xx;
          if (given[k])
            continue;
          given[k] = 2;  // ring: its own depth
          const auto &p = cloud (x0_ + xx, y0_ + yy);
          data_[k] = toMillimetres (p.x, p.y, p.z);
        }
    }
}
}  // namespace agex
