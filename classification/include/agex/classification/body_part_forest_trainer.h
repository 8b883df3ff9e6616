#pragma once
// Training agex::BodyPartForest from labelled frames (Shotton et al. CVPR 2011 Sec. 3.4):
// per tree, pixels sampled per frame, nodes grown greedily by information gain over random
// depth-comparison features and thresholds. Independent of how the frames are produced.

#include <agex/classification/body_part_forest.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/types.h>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace agex
{
/** One training frame: an organized cloud (metres), the body's pixels (its foreground, as the
  * labelling will see it) and each body pixel's class. */
struct BodyPartTrainingFrame
{
  pcl::PointCloud<pcl::PointXYZ>::ConstPtr cloud;
  pcl::Indices body;         ///< row-major pixel indices of the body
  std::vector<int> classes;  ///< per body pixel: a class index, or -1 (foreground, not sampled)
  float fx = 525.f, fy = 525.f;  ///< focal lengths of the frame (pixels)
};

struct BodyPartForestTrainerParams
{
  int trees = 3;
  int max_depth = 20;           ///< at most BodyPartForest::kMaxDepth
  int features_per_node = 200;  ///< random offset pairs tried per node
  int thresholds_per_feature = 20;  ///< thresholds tried per feature (from sampled feature values)
  int pixels_per_frame = 1000;  ///< labelled pixels sampled per frame for each tree (all if fewer)
  /** Largest offset component (pixel·metres at reference_focal: at 1 m a probe this many pixels
    * away, i.e. offset_range / reference_focal metres on the body at any depth). */
  int offset_range = 150;
  /** Probability that a feature's second probe is the pixel itself (v = 0), Shotton's unary
    * features; PCL's trees use them too. */
  float unary_probability = 0.3f;
  int min_samples_per_leaf = 10;  ///< no split leaves a child with fewer samples
  double min_gain = 1e-4;         ///< a node becomes a leaf when no split gains this much (bits)
  /** Weigh classes inversely to their sampled frequency (in the gains and the leaf
    * distributions), so that small parts (hands) are not drowned by the torso. */
  bool balance_classes = true;
  float reference_focal = BodyPartForest::kPclFocalLength;  ///< the model's offset units
  int foreground_dilation = 0;  ///< as BodyPartLabeling::setForegroundDilation at test time
  std::uint64_t seed = 1;
  int threads = 1;  ///< results do not depend on it
};

/** \brief Trains a BodyPartForest.
  *
  * Each tree draws its own sample: from every frame, pixels_per_frame labelled body pixels
  * uniformly without replacement. Nodes are grown level by level; at each node
  * features_per_node offset pairs (u, v) with components uniform in [-offset_range,
  * offset_range] (v = 0 with unary_probability) and, per feature, thresholds_per_feature
  * thresholds (feature values of random samples at the node, minus a half) are tried; the
  * split of largest Shannon information gain is kept if it gains at least min_gain and
  * leaves min_samples_per_leaf samples on each side. A node is a leaf at max_depth, when pure
  * or when it cannot be split; its distribution is its (class-balanced) histogram.
  *
  * Features are computed exactly as BodyPartForest evaluates them (forestFeature), on the
  * frames' ForestDepthImage (body pixels, background elsewhere), with each frame's focal
  * lengths scaled to reference_focal. Deterministic for a seed, whatever the threads. */
class BodyPartForestTrainer
{
public:
  using Progress = std::function<void (std::size_t done, std::size_t total)>;

  BodyPartForestTrainer ();

  void setParams (const BodyPartForestTrainerParams &params) { params_ = params; }
  const BodyPartForestTrainerParams &getParams () const { return params_; }

  /** The classes to train (default head, hand, foot, other_body, mapped to those parts). */
  void setClasses (const std::vector<BodyPartForest::ClassInfo> &classes) { classes_ = classes; }
  const std::vector<BodyPartForest::ClassInfo> &getClasses () const { return classes_; }

  /** \brief Trains a forest; progress (if given) is called after each tree level with
    * (levels done, trees x (max_depth + 1)).
    * \throws std::invalid_argument on bad parameters or frames (naming the frame), and
    *         std::runtime_error if no frame has a labelled pixel */
  BodyPartForest::Ptr train (const std::vector<BodyPartTrainingFrame> &frames, const Progress &progress = Progress ()) const;

  /** Samples drawn by the last train () call, summed over trees, per class. */
  const std::vector<std::size_t> &sampledPerClass () const { return sampled_; }

private:
  BodyPartForestTrainerParams params_;
  std::vector<BodyPartForest::ClassInfo> classes_;
  mutable std::vector<std::size_t> sampled_;
};
}  // namespace agex
