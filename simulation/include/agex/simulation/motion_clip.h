#pragma once
// A motion capture clip ready to pose bodies: a BVH file and the joints the body hangs on
// (doc/synthetic.md, "Motion: BVH").
#include <agex/simulation/bvh.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace agex
{
/** The joints the body model hangs on, found by name in a BVH skeleton. Two naming
  * schemes are known: CMU ASF conversions (LeftUpLeg, LeftLeg, LeftFoot, LeftToeBase,
  * Spine, Spine1, Neck, Head, LeftArm, LeftForeArm, LeftHand, LeftHandIndex1) and the
  * bvh11 / CMU 131 scheme (LeftHip, LeftKnee, LeftAnkle, LeftToe, Chest, Chest2,
  * lowerneck, Head, LeftShoulder, LeftElbow, LeftWrist, LFingers); index 0 = left. */
struct SkeletonMap
{
  int root = -1, spine_base = -1, spine_mid = -1, neck = -1, head = -1, head_end = -1;
  int shoulder[2] = {-1, -1}, elbow[2] = {-1, -1}, wrist[2] = {-1, -1}, hand_end[2] = {-1, -1};
  int hip[2] = {-1, -1}, knee[2] = {-1, -1}, ankle[2] = {-1, -1}, toe[2] = {-1, -1}, toe_end[2] = {-1, -1};
  /** Rest-pose directions in the file's world frame: the subject's left, up and forward. */
  Eigen::Matrix3d rest_basis = Eigen::Matrix3d::Identity ();

  /** \brief Finds the joints. \throws BvhError naming the file and the missing joint */
  static SkeletonMap find (const BvhMotion &motion);
};

/** A motion capture clip ready to pose bodies. */
struct MotionClip
{
  BvhMotion motion;
  SkeletonMap map;
  double scale = 1.0;          ///< metres per file unit
  bool scale_auto = true;      ///< scale was detected (autoBvhScale)
  std::string sequence;        ///< the file's stem

  /** \brief Reads a BVH file; scale <= 0 means auto (autoBvhScale).
    * \throws BvhError naming the file (and line) */
  static MotionClip load (const std::string &path, double scale = 0.0);
};
}  // namespace agex
