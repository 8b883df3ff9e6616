#pragma once
// Where a synthetic camera stands and looks.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace agex
{
/** The camera at `camera` looking at `aim` (Y up: x right, y down, z forward), then
  * pitched by `pitch` about its x axis and rolled by `roll` about its view axis. */
Eigen::Isometry3d worldToCamera (const Eigen::Vector3d &camera, const Eigen::Vector3d &aim, double roll, double pitch);
}  // namespace agex
