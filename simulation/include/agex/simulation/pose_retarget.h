#pragma once
// Poses of motion capture skeletons carried over to the pose skeleton (PoseSkeleton):
// the joint-name maps of the known schemes and the retargeting (doc/synthetic.md, "Pose
// bank").
//
// Retargeting by segment directions: the source frame is posed by forward kinematics, the
// landmarks named by the scheme's map (PoseTargets) are read off, and PoseSkeleton::
// solvePose turns the pose skeleton's segments to point where the source's do. This needs
// no rest pose of the source, which matters for the Character Creator files: their joint
// frames are the bones' own (a zero-channel "rest" has the legs pointing up), so their
// rotations cannot be applied to another skeleton as they are.

#include <agex/simulation/bvh.h>
#include <agex/simulation/pose_skeleton.h>

#include <string>
#include <vector>

namespace agex
{
enum class SkeletonScheme
{
  CharacterCreator,  ///< CC_Base_Hip, CC_Base_L_Thigh, ... (cmu_cc/), centimetres
  Cmu                ///< Hips, LeftUpLeg, ..., Neck1, Head (Hahne's and CMU ASF conversions, bvh units)
};

/** "character-creator" or "cmu". */
const char *skeletonSchemeName (SkeletonScheme scheme);

/** Which joint of a scheme gives each landmark of PoseTargets (index 0 = left). Empty:
  * the scheme has none (the landmark is derived, see PoseRetarget). */
struct JointNameMap
{
  SkeletonScheme scheme = SkeletonScheme::Cmu;
  std::string root, chest, neck, head;
  std::string eye[2];  ///< head orientation from the eyes (else the head joint's rotation)
  std::string hip[2], knee[2], ankle[2], toe[2], shoulder[2], elbow[2], wrist[2], hand_end[2];
  /** Palm across: from pinky base to index base (else the wrist's rotation of +Z). */
  std::string index_base[2], pinky_base[2];
  /** Joints whose rotations all zero mark a broken capture of that leg (Hahne's 111_02). */
  std::vector<std::string> leg_chain[2];

  static JointNameMap of (SkeletonScheme scheme);
};

class PoseRetarget
{
public:
  /** \brief Recognises the scheme of a skeleton by its joint names.
    * \throws BvhError naming the file if no known scheme fits */
  static SkeletonScheme detect (const BvhMotion &motion);

  /** \brief Binds a motion to its scheme's map. scale: metres per file unit (<= 0: the
    * scheme's own: 0.01 for Character Creator, kCmuBvhUnit for CMU, 1 if the file's rest
    * height says metres). \throws BvhError naming the file and a missing joint */
  PoseRetarget (const BvhMotion &motion, double scale = 0.0);

  SkeletonScheme scheme () const { return map_.scheme; }
  double scale () const { return scale_; }

  /** \brief The landmarks of a frame, metres. \throws std::out_of_range for a bad frame */
  PoseTargets targets (int frame) const;
  /** \brief The frame on the pose skeleton: root at the source's, scaled by leg lengths. */
  PoseFrame pose (int frame) const;
  /** True if every rotation channel of one leg's chain is exactly zero in this frame
    * while the other leg moves: a leg the capture lost (doc/synthetic.md). */
  bool zeroedLeg (int frame) const;

private:
  struct Index
  {
    int root = -1, chest = -1, neck = -1, head = -1, eye[2] = {-1, -1};
    int hip[2], knee[2], ankle[2], toe[2], shoulder[2], elbow[2], wrist[2], hand_end[2];
    int index_base[2] = {-1, -1}, pinky_base[2] = {-1, -1};
    std::vector<int> leg_chain[2];
  };
  const BvhMotion *motion_;
  JointNameMap map_;
  Index index_;
  double scale_ = 1.0;
  double leg_ratio_ = 1.0;  ///< pose skeleton's leg length / the source's
};
}  // namespace agex
