#pragma once
// Per-pixel body-part classes of labelled frames, for training and scoring a body-part forest
// (agex::BodyPartForestTrainer, agex::BodyPartLabeling): exact from a dataset's part-label
// images (synthetic frames), or weak from the labelled tips and bases (real frames), on the
// pixels the detector's pipeline keeps. doc/forest.md describes both rules.

#include <agex/classification/body_part_forest_trainer.h>
#include <agex/classification/body_part_label_point.h>
#include <agex/detection/depth_pipeline.h>
#include <agex/io/dataset.h>

#include <nlohmann/json_fwd.hpp>

#include <array>
#include <map>
#include <string>
#include <vector>

namespace agex
{
/** Weak labels from tips and bases: per part (head, hand, foot), how far from the tip towards
  * the base and how far from that axis a body pixel may be to be the part. */
struct WeakPartLabelParams
{
  std::array<float, 3> reach{{0.25f, 0.20f, 0.22f}};   ///< metres along tip -> base
  std::array<float, 3> radius{{0.12f, 0.06f, 0.07f}};  ///< metres from the axis
  float beyond_tip = 0.03f;                            ///< metres the part may extend past the tip
  /** \throws std::invalid_argument unless every reach and radius is in (0, 1] and beyond_tip in [0, 0.2] */
  void validate () const;
};

/** A frame's body pixels with their classes (LabelPart: head, hand, foot, other body; -1: ignore). */
struct PartLabelledFrame
{
  std::string id;
  pcl::PointCloud<pcl::PointXYZ>::ConstPtr cloud;  ///< what the forest reads
  pcl::Indices body;
  std::vector<int> classes;  ///< per body pixel
  bool exact = false;        ///< from a part-label image
  DepthPipelineResult prepared;  ///< the pipeline run it came from
};

/** The LabelPart of a dataset's part-label id, by its name in dataset.json: "head" -> head,
  * "*hand" -> hand, "*foot" -> foot, "body" (part unknown) -> ignore (-1), anything else ->
  * other body. */
int labelPartOfName (const std::string &name);

/** \brief The body pixels of frame id and their classes. The pipeline (params) runs on the
  * frame; its meshes are the body. With a part-label image (Dataset::hasPartLabels) the
  * classes are exact: every finite pixel of the filtered frame whose image id is a body part
  * (the meshes are not needed then). Otherwise they are weak: a mesh pixel is part p when it
  * lies within reach of a visible tip of p along tip -> base, within radius of that axis
  * and at most beyond_tip past the tip (the nearest such tip's part), else other body; a frame
  * with a tip or base it cannot place gives false (it would teach "other body" where a part
  * is). raw_depth: the forest reads the frame's own depth at those pixels, not the filtered.
  * \return false if the frame yields no body pixel or cannot be weakly labelled
  * \throws DatasetError on a damaged frame or label image */
bool partLabelledFrame (const Dataset &dataset, const std::string &id, const DepthPipelineParams &params,
                        const WeakPartLabelParams &weak, bool raw_depth, PartLabelledFrame &out);

/** \brief Per-pixel scores of part labels against a frame's classes: the confusion of the four
  * parts (rows: truth; columns: head, hand, foot, other body, none), accuracy and per-part
  * recall, and per labelled tip whether its part was found (at least 20% of the body pixels
  * within 10 cm of the tip carry the part). */
class PartLabelEvaluation
{
public:
  void addFrame (const PartLabelledFrame &frame, const pcl::PointCloud<BodyPartLabelPoint> &labels);
  const std::array<std::array<std::size_t, 5>, 4> &confusion () const { return confusion_; }
  double accuracy () const;
  /** NaN for a part without labelled pixels. */
  double recall (int part) const;
  double meanClassRecall () const;
  int frames () const { return frames_; }
  nlohmann::json report () const;

private:
  std::array<std::array<std::size_t, 5>, 4> confusion_{};
  int frames_ = 0;
};
}  // namespace agex
