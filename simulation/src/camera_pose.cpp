#include <agex/simulation/camera_pose.h>

namespace agex
{
Eigen::Isometry3d
worldToCamera (const Eigen::Vector3d &camera, const Eigen::Vector3d &aim, double roll, double pitch)
{
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY ();
  const Eigen::Vector3d forward = (aim - camera).normalized ();
  const Eigen::Vector3d right = forward.cross (up).normalized ();
  const Eigen::Vector3d down = forward.cross (right);
  Eigen::Matrix3d rotation;
  rotation.row (0) = right;
  rotation.row (1) = down;
  rotation.row (2) = forward;
  rotation = Eigen::AngleAxisd (roll, Eigen::Vector3d::UnitZ ()).toRotationMatrix () *
             Eigen::AngleAxisd (pitch, Eigen::Vector3d::UnitX ()).toRotationMatrix () * rotation;
  Eigen::Isometry3d world_to_camera = Eigen::Isometry3d::Identity ();
  world_to_camera.linear () = rotation;
  world_to_camera.translation () = -(rotation * camera);
  return world_to_camera;
}
}  // namespace agex
