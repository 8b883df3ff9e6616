#pragma once

#include <agex/common/body_part.h>

#include <nlohmann/json_fwd.hpp>

#include <Eigen/Core>

#include <vector>

namespace agex
{
/** \brief One body part found in a depth frame: what agex::BodyPartDetector, the
  * sliding-window baseline and the evaluations all speak. */
struct BodyPartDetection
{
  BodyPart part = BodyPart::Head;
  float confidence = 0.f;  ///< in [0, 1]
  float margin = 0.f;      ///< the classifier's boosted margin for that class
  Eigen::Vector3f position = Eigen::Vector3f::Zero ();     ///< metres, camera frame
  /** Unit vector along the limb towards the tip; zero when unknown (sliding windows). */
  Eigen::Vector3f orientation = Eigen::Vector3f::Zero ();
  int u = 0, v = 0;  ///< pixel column and row in the frame
  int rank = 0;      ///< rank of the AGEX point it was found at (0: not an AGEX point)
  int mesh = -1;     ///< surface mesh it lies on (-1: unknown)
  int person = -1;   ///< the person it belongs to (DepthPipelineResult::persons; -1: unknown)
  /** Sliding windows: the window's extent over the trained one (AGEX points: 1). */
  float scale = 1.f;
};

/** The detection as agex's JSON outputs write it: class, confidence, margin, position,
  * orientation, pixel, rank, mesh, person. */
nlohmann::json toJson (const BodyPartDetection &detection);
}  // namespace agex
