#pragma once
// Body-part proposals from a label cloud as PCL's gpu/people pipeline makes them: labels
// smoothed within a metric window, connected blobs of one part, each blob's extremity
// (its end away from the body's centre) as the part's position (doc/forest.md, "Forest mode").

#include <agex/classification/body_part_label_point.h>
#include <agex/classification/part_modes.h>

#include <pcl/point_cloud.h>
#include <pcl/types.h>

#include <array>
#include <functional>
#include <string>
#include <vector>

namespace agex
{
struct PartBlobParams
{
  /** Half-size (metres on the body) of the label smoothing window: r = round (this fx / z)
    * pixels around a pixel at depth z (PCL's 5x5 is 2 pixels at about 2 m and 525 px).
    * 0: no smoothing. [0, 0.05] */
  float smoothing_radius = 0.008f;
  /** Only pixels within this depth of the centre vote in the smoothing (PCL: 300 mm). (0, 2] */
  float smoothing_depth_window = 0.3f;
  /** Neighbouring pixels of one part closer than this (3D, metres) are one blob (PCL's
    * cluster tolerance, 5 cm). (0, 0.5] */
  float connect_distance = 0.05f;
  /** Blobs of a smaller visible area (m^2: the sum of z^2 / (fx fy) over its pixels) are
    * dropped: speckles of one part inside another. [0, 1] */
  float min_area = 0.0008f;
  /** The blob's extremity is its pixels within this distance (metres, along the direction
    * from the body's centre to the blob) of its farthest one; the part's position is the one
    * of them nearest their median. (0, 0.2] */
  float extremity_depth = 0.03f;
  /** Focal lengths (pixels) of the frame. */
  float fx = 525.f, fy = 525.f;
  /** Weighted area (m^2) at which confidence is 0.5: head, hand, foot, other body (as
    * PartModeParams::reference_area). */
  std::array<float, kLabelPartCount> reference_area{{0.03f, 0.01f, 0.012f, 0.2f}};
  /** Parts to find blobs of (default head, hand, foot). */
  std::array<bool, kLabelPartCount> parts{{true, true, true, false}};

  /** \throws std::invalid_argument naming the setting (name (key)) and its range */
  void validate (const std::function<std::string (const std::string &key)> &name) const;
};

/** \brief Finds part blobs in an organized label cloud, given the body's pixels:
  *
  * The body pixels are those given with a label (>= 0) and a finite point: a strided forest
  * pass must fill the pixels between its representatives (StrideFill::Copy), as it does by
  * default.
  *
  * - smoothing: each body pixel takes the most frequent part label among the body pixels
  *   of its window (smoothing_radius on the body, scaled by fx / z) within
  *   smoothing_depth_window of its depth; its own label on a tie (PCL's smoothKernel over
  *   parts);
  * - blobs: 8-connected pixels of one (smoothed) part label whose 3D distance is below
  *   connect_distance; blobs under min_area are dropped;
  * - the body's centre: the centroid of the "other body" pixels (of all without any);
  * - per blob a PartMode: tip and position at its extremity (finger tips, the top of the
  *   head, the toes): of its pixels within extremity_depth of the farthest along the
  *   direction from the body's centre to the blob's centroid, the one nearest their median,
  *   so that a silhouette pixel of mixed depth is not the part's position; mass = its
  *   pixels' part probability times z^2 / (fx fy), confidence = mass / (mass +
  *   reference_area), direction = that direction, support = its pixels.
  *
  * Modes are returned per part (head first), most confident first. Deterministic. */
class PartBlobEstimation
{
public:
  /** \throws std::invalid_argument on a setting out of range (PartBlobParams::validate) */
  void setParams (const PartBlobParams &params);
  const PartBlobParams &getParams () const { return params_; }

  /** \return false (PCL_ERROR, no blobs) if labels is not organized */
  bool compute (const pcl::PointCloud<BodyPartLabelPoint> &labels, const pcl::Indices &body,
                std::vector<PartMode> &blobs) const;

private:
  PartBlobParams params_;
};
}  // namespace agex
