#pragma once
// The agex pose skeleton: one fixed, CMU-like skeleton (joint names of the CMU ASF
// conversions, so SkeletonMap finds it) that every pose of a PoseBank is expressed on,
// whatever skeleton it came from (doc/synthetic.md, "Pose bank"). Metres, Y up, the
// subject faces +Z with its left at +X; the rest pose (all channels zero) is a T-pose
// whose joint frames are the world's, so a joint's rotation is its rotation from the
// T-pose and every body builder (buildBody, buildMeshBody) poses it unchanged.
//
// A pose is given as target positions of the body's landmarks (PoseTargets) and turned
// into joint rotations by solvePose: each segment is swung from its parent's frame to
// point where the target segment points; the twist of a limb comes from the bend of
// its middle joint (elbow, knee) and, for a straight limb, from the palm or the foot.

#include <agex/simulation/bvh.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <string>
#include <vector>

namespace agex
{
/** Landmarks of a pose in a common world frame (any unit, any origin; Y up). Index 0 = left. */
struct PoseTargets
{
  Eigen::Vector3d root = Eigen::Vector3d::Zero ();  ///< pelvis centre
  Eigen::Vector3d chest = Eigen::Vector3d::Zero (), neck = Eigen::Vector3d::Zero (), head = Eigen::Vector3d::Zero ();
  /** Rotation of the head from the T-pose (world frame). */
  Eigen::Matrix3d head_rotation = Eigen::Matrix3d::Identity ();
  std::array<Eigen::Vector3d, 2> hip, knee, ankle, toe, shoulder, elbow, wrist, hand_end;
  /** Per hand: a vector across the palm toward the thumb side (in the T-pose, palms down,
    * it points forward, +Z). Only its part across the hand's axis is used. */
  std::array<Eigen::Vector3d, 2> palm_across;
};

/** A pose on the pose skeleton: the root's position (metres) and each joint's rotation
  * in its parent's frame (PoseSkeleton::Joint order). */
struct PoseFrame
{
  Eigen::Vector3d root = Eigen::Vector3d::Zero ();
  std::vector<Eigen::Matrix3d> local;
};

class PoseSkeleton
{
public:
  enum Joint
  {
    Hips,
    LeftUpLeg,
    LeftLeg,
    LeftFoot,
    LeftToeBase,
    RightUpLeg,
    RightLeg,
    RightFoot,
    RightToeBase,
    LowerBack,
    Spine,
    Spine1,
    Neck,
    Head,
    LeftArm,
    LeftForeArm,
    LeftHand,
    LeftHandIndex1,
    RightArm,
    RightForeArm,
    RightHand,
    RightHandIndex1,
    kJoints
  };

  static const char *jointName (int joint);
  static int parent (int joint);
  /** Offset from the parent in the T-pose, metres (the root's: its rest position). */
  static Eigen::Vector3d offset (int joint);
  /** Global joint positions of a pose (metres), PoseSkeleton::Joint order. */
  static std::vector<Eigen::Vector3d> positions (const PoseFrame &pose);
  /** Height of the T-pose, soles to the top of the head, metres. */
  static double standingHeight ();
  /** Hip joint to ankle in the T-pose, metres. */
  static double legLength ();

  /** \brief Joint rotations that make the skeleton take the targets' pose (see the
    * file's comment); the root is placed at targets.root times root_scale. */
  static PoseFrame solvePose (const PoseTargets &targets, double root_scale);

  /** \brief A BVH motion on the pose skeleton, one frame per pose (ZXY Euler channels).
    * \throws BvhError if poses is empty or a rotation is not finite */
  static BvhMotion motion (const std::vector<PoseFrame> &poses, const std::string &name);
};

/** Rotation that takes the global frame `parent` to one whose `rest_direction` (a
  * direction of the T-pose) points along `target`, by the shortest turn (swing only). */
Eigen::Matrix3d swingFrom (const Eigen::Matrix3d &parent, const Eigen::Vector3d &rest_direction,
                           const Eigen::Vector3d &target);
}  // namespace agex
