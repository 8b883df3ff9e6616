#pragma once
// Body-part proposals from a label cloud: per part, the modes of the pixels' probability
// density (mean shift, Shotton et al. CVPR 2011 Sec. 4), each with its mass, its supporting
// pixels, its principal direction and its tip. Independent of any detector (doc/forest.md).

#include <agex/classification/body_part_label_point.h>

#include <pcl/point_cloud.h>
#include <pcl/types.h>

#include <Eigen/Core>

#include <array>
#include <vector>

namespace agex
{
/** One mode of a part's density. */
struct PartMode
{
  int part = kLabelNone;  ///< LabelPart
  /** The mode (metres, camera frame): on the body's visible surface, not pushed inwards. */
  Eigen::Vector3f position = Eigen::Vector3f::Zero ();
  /** Sum of the supporting pixels' weights p z^2 over fx fy: the part's probability-weighted
    * visible area in m^2 (a pixel at depth z covers z^2 / (fx fy) m^2 facing the camera). */
  float mass = 0.f;
  /** mass / (mass + reference area of the part): in [0, 1), 0.5 when the weighted area is
    * the part's reference area (PartModeParams::reference_area). */
  float confidence = 0.f;
  /** Mean part probability of the supporting pixels. */
  float mean_probability = 0.f;
  /** The pixels (indices into the label cloud) whose mean shift reached this mode. */
  pcl::Indices support;
  /** Unit direction pointing away from the body along the part (see PartModeEstimation). */
  Eigen::Vector3f direction = Eigen::Vector3f::Zero ();
  /** The extremity: the supporting pixel farthest from the mode along direction. */
  Eigen::Vector3f tip = Eigen::Vector3f::Zero ();
  int tip_index = -1;  ///< its index in the label cloud
};

struct PartModeParams
{
  /** Mean-shift bandwidth b per part (metres, 0.0001-10; Gaussian kernel exp(-|x - x_i|^2 / b^2),
    * cut at 3 b): head, hand, foot, other body. Shotton et al. learned 0.06-0.07 m for their joints. */
  std::array<float, kLabelPartCount> bandwidth{{0.065f, 0.05f, 0.06f, 0.10f}};
  /** Pixels whose part probability is below this are not part of the density (Shotton's
    * lambda_c). */
  float probability_threshold = 0.2f;
  /** Focal lengths (pixels) of the frame, for the pixel areas of mass. */
  float fx = 525.f, fy = 525.f;
  /** Weighted area (m^2) at which confidence is 0.5: head, hand, foot, other body. */
  std::array<float, kLabelPartCount> reference_area{{0.03f, 0.01f, 0.012f, 0.2f}};
  /** Parts to find modes of (default head, hand, foot). */
  std::array<bool, kLabelPartCount> parts{{true, true, true, false}};
  int max_iterations = 50;
  float convergence = 1e-4f;  ///< metres a mean-shift step must fall below to stop
  /** Labelled pixels outside the support within this distance (metres) of a supporting pixel
    * are where the part touches the body (its base), from which the direction points away. */
  float contact_radius = 0.04f;
  /** The principal axis is the part's direction when its standard deviation is at least
    * this many times the second one; rounder parts point from their base to the mode. */
  float elongation = 1.5f;
  /** Modes with fewer supporting pixels are dropped. */
  int min_support = 3;
  /** Organized clouds: only the pixels at multiples of pixel_step in both image axes are
    * samples, each standing for pixel_step^2 pixels (the representatives of a forest pass at
    * that stride; the others only copy them). 1: every pixel. */
  int pixel_step = 1;
};

/** \brief Finds part modes in a label cloud (any cloud of BodyPartLabelPoint; organized or
  * not), per part in PartModeParams::parts:
  *
  * - density: the labelled pixels (finite point, label >= 0) with part probability p >=
  *   probability_threshold, weighted w = p z^2 (Shotton et al. Sec. 4: z^2 makes the weight
  *   proportional to the surface a pixel covers, so a part counts the same at any distance);
  * - mean shift with a Gaussian kernel of the part's bandwidth from one seed per bandwidth-
  *   sized grid cell (the weighted mean of its pixels), seeds in cell order; seeds whose modes
  *   lie within half a bandwidth of each other are one mode; a path whose step lands in a cell
  *   a quarter bandwidth wide where a step of an earlier path that reached a mode landed joins
  *   that mode (its basin of attraction); a pixel supports the mode its cell's seed reached;
  * - direction: the base is the centroid of the labelled pixels outside the support (other
  *   parts, other modes) within contact_radius of a supporting pixel, where the part touches
  *   the rest of the body (the
  *   body centroid if it touches nothing); if the support is
  *   elongated (see elongation) the direction is its weighted principal axis, signed to point
  *   away from the base, else the unit vector from the base to the mode;
  * - tip: the supporting pixel with the largest projection on the direction from the mode.
  *
  * Modes are returned per part (head first), most confident first. Deterministic. */
class PartModeEstimation
{
public:
  void setParams (const PartModeParams &params) { params_ = params; }
  const PartModeParams &getParams () const { return params_; }

  /** \return false (PCL_ERROR, no modes) if a parameter is out of range */
  bool compute (const pcl::PointCloud<BodyPartLabelPoint> &labels, std::vector<PartMode> &modes) const;

  /** \brief compute () looking only at the given pixels of labels (any order, e.g. those the
    * labelling stage was given), not at the whole frame: the same modes when every labelled
    * pixel is among them. */
  bool compute (const pcl::PointCloud<BodyPartLabelPoint> &labels, const pcl::Indices &pixels,
                std::vector<PartMode> &modes) const;

private:
  bool computeFrom (const pcl::PointCloud<BodyPartLabelPoint> &labels, const pcl::Indices *pixels,
                    std::vector<PartMode> &modes) const;

  PartModeParams params_;
};
}  // namespace agex
