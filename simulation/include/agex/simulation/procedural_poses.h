#pragma once
// Procedural poses of what people do in front of a camera and walks do not: hands on
// the hips, in pockets, crossed arms, hands behind the back, arms raised, pointing
// forward, a hand near the face, waving, reaching sideways; standing, stepping, kneeling,
// seated (doc/synthetic.md, "Procedural poses"). Each pose is drawn from a seeded
// SynthRng within the documented joint limits (jointLimits) and made on the pose
// skeleton (PoseSkeleton), facing +Z: the scene turns it toward the camera or away.

#include <agex/simulation/pose_skeleton.h>
#include <agex/simulation/synthetic_scene.h>

#include <cstdint>
#include <string>
#include <vector>

namespace agex
{
enum class ArmPose
{
  Relaxed,
  HandsOnHips,
  HandsInPockets,
  CrossedArms,
  HandsBehindBack,
  OneArmRaised,
  BothArmsRaised,
  PointingForward,  ///< the right forearm along the body's forward (+Z): face the body to the camera to point at it
  HandNearFace,
  Waving,
  ReachingSideways,
  kCount
};

enum class LegPose
{
  Standing,
  Stepping,
  Kneeling,
  Seated,
  kCount
};

const char *armPoseName (ArmPose pose);
const char *legPoseName (LegPose pose);

/** One anatomical range of motion, degrees (doc/synthetic.md lists them). */
struct JointLimit
{
  const char *joint;
  const char *motion;
  double min_degrees, max_degrees;
};

/** Joint angles of a pose, degrees, measured from its skeleton the way the limits are
  * defined: side 0 = left. */
struct PoseAngles
{
  double trunk_flexion = 0, trunk_lateral = 0, trunk_twist = 0, head_yaw = 0, head_pitch = 0;
  double shoulder_elevation[2] = {0, 0};  ///< 0 hanging, 90 horizontal, 180 straight up
  double shoulder_plane[2] = {0, 0};      ///< 0 to the side, 90 forward, > 90 across, < 0 behind
  double elbow_flexion[2] = {0, 0};
  double hip_flexion[2] = {0, 0}, hip_abduction[2] = {0, 0}, knee_flexion[2] = {0, 0};
};

struct ProceduralPose
{
  ArmPose arms = ArmPose::Relaxed;
  LegPose legs = LegPose::Standing;
  PoseFrame frame;
};

class ProceduralPoses
{
public:
  /** The limits every procedural pose keeps to. */
  static const std::vector<JointLimit> &jointLimits ();
  /** \brief Angles of a pose on the pose skeleton. */
  static PoseAngles measure (const PoseFrame &pose);
  /** Names of the limits a pose's angles break (empty: within all). The shoulder's plane
    * is only checked above 30 degrees of elevation, where it is defined. */
  static std::vector<std::string> violations (const PoseAngles &angles);

  /** \brief One pose of the given kinds. */
  static ProceduralPose make (ArmPose arms, LegPose legs, SynthRng &rng);
  /** \brief count poses (0-100000), kinds drawn evenly, all from the seed.
    * \throws std::invalid_argument for a count out of range */
  static std::vector<ProceduralPose> generate (int count, std::uint64_t seed);
};
}  // namespace agex
