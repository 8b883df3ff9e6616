#pragma once
// How the forest mode turns a frame into parts: which pixels the forest labels (the person
// as segmented, or the meshes left after the cleaning stages) and how labels become parts
// (PCL-style blobs at their extremities, or mean-shift modes). doc/forest.md, "Forest mode".

#include <agex/classification/body_part_forest.h>
#include <agex/classification/body_part_label_point.h>
#include <agex/classification/part_blobs.h>
#include <agex/classification/part_modes.h>
#include <agex/detection/depth_pipeline.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace agex
{
/** The pixels the forest mode labels. */
enum class ForestInput
{
  /** What the forest was trained on: Persons for a forest of PCL's 32 labels (PCL's trees,
    * trained on whole rendered people), Meshes for ours (trained on the pipeline's meshes,
    * agex_train_forest) */
  Automatic,
  Persons,  ///< the persons as segmented, at the frame's own depth: no cleaning stage thins them
  Meshes    ///< the pipeline's meshes on its filtered cloud (what a fused model was trained on)
};
/** "automatic", "persons", "meshes". */
const char *forestInputName (ForestInput input);
/** Inverse of forestInputName; false for an unknown name. */
bool parseForestInput (const std::string &name, ForestInput &input);

/** How the forest mode turns labels into parts. */
enum class PartProposals
{
  Blobs,  ///< agex::PartBlobEstimation: smoothed labels, connected blobs, each at its extremity
  Modes   ///< agex::PartModeEstimation: mean-shift modes, each at its tip
};
/** "blobs", "modes". */
const char *partProposalsName (PartProposals proposals);
/** Inverse of partProposalsName; false for an unknown name. */
bool parsePartProposals (const std::string &name, PartProposals &proposals);

struct ForestPartSettings
{
  ForestInput input = ForestInput::Automatic;
  PartProposals proposals = PartProposals::Blobs;
  /** Input Persons: a person's pixels less than this (metres) above the pipeline's floor are
    * the floor under the feet, not the person (the person is segmented before the floor is
    * removed). [0, 0.5] */
  float floor_margin = 0.04f;
  /** The blobs' settings; fx and fy are the frame's (set by forestParts). */
  PartBlobParams blobs;

  /** \throws std::invalid_argument naming the setting (name (key)) and its range */
  void validate (const std::function<std::string (const std::string &key)> &name) const;
};

/** \brief The forest mode's part labels and parts of one frame. Input Automatic is Persons or
  * Meshes by the forest (ForestInput::Automatic). Input Persons labels the
  * union of prepared.persons on frame (the pipeline's input as XYZ), falling back to the
  * meshes on prepared.filtered when the pipeline isolated no person (isolate_people off);
  * Meshes labels the meshes (labelPersonParts). Proposals Blobs: PartBlobEstimation on the
  * labelled pixels; Modes: PartModeEstimation as labelPersonParts. stride 0: forestStrideFor.
  * ms, if given: (labelling, proposals) milliseconds.
  * \return false (labels and parts empty) without pixels to label, a forest or a focal length */
bool forestParts (const DepthPipelineResult &prepared, const pcl::PointCloud<pcl::PointXYZ>::ConstPtr &frame,
                  const BodyPartForest::ConstPtr &forest, float fx, float fy, int stride,
                  const ForestPartSettings &settings, pcl::PointCloud<BodyPartLabelPoint> &labels,
                  std::vector<PartMode> &parts, std::pair<double, double> *ms = nullptr);
}  // namespace agex
