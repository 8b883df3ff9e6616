#include <agex/simulation/procedural_poses.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace agex
{
namespace
{
constexpr double kDeg = M_PI / 180.0;
constexpr double kUpperArm = 0.29, kForearm = 0.26, kHand = 0.18;

Eigen::Matrix3d
rx (double degrees)
{
  return Eigen::AngleAxisd (degrees * kDeg, Eigen::Vector3d::UnitX ()).toRotationMatrix ();
}
Eigen::Matrix3d
ry (double degrees)
{
  return Eigen::AngleAxisd (degrees * kDeg, Eigen::Vector3d::UnitY ()).toRotationMatrix ();
}
Eigen::Matrix3d
rz (double degrees)
{
  return Eigen::AngleAxisd (degrees * kDeg, Eigen::Vector3d::UnitZ ()).toRotationMatrix ();
}

double
angleBetween (const Eigen::Vector3d &a, const Eigen::Vector3d &b)
{
  return std::atan2 (a.cross (b).norm (), a.dot (b)) / kDeg;
}

Eigen::Vector3d
across (const Eigen::Vector3d &v, const Eigen::Vector3d &axis)
{
  return v - v.dot (axis) * axis;
}

/** Builds a pose's landmarks from angles and wrist targets (see make). */
class PoseBuilder
{
public:
  PoseBuilder (SynthRng &rng) : rng_ (rng) {}

  double u (double lo, double hi) { return rng_.uniform (lo, hi); }

  void torso (double flexion, double lateral, double twist, double yaw, double pitch)
  {
    pelvis_ = Eigen::Matrix3d::Identity ();
    chest_ = pelvis_ * ry (twist) * rz (-lateral) * rx (flexion);
    t_.root = Eigen::Vector3d (0, PoseSkeleton::offset (PoseSkeleton::Hips).y (), 0);
    t_.chest = t_.root + pelvis_ * Eigen::Vector3d (0, 0.08, 0) + chest_ * Eigen::Vector3d (0, 0.26, 0);
    t_.neck = t_.chest + chest_ * PoseSkeleton::offset (PoseSkeleton::Neck);
    t_.head = t_.neck + chest_ * PoseSkeleton::offset (PoseSkeleton::Head);
    t_.head_rotation = chest_ * ry (yaw) * rx (pitch);
    for (int s = 0; s < 2; ++s)
    {
      t_.shoulder[s] = t_.chest + chest_ * PoseSkeleton::offset (s == 0 ? PoseSkeleton::LeftArm : PoseSkeleton::RightArm);
      t_.hip[s] = t_.root + pelvis_ * PoseSkeleton::offset (s == 0 ? PoseSkeleton::LeftUpLeg : PoseSkeleton::RightUpLeg);
    }
  }

  /** An arm from angles: elevation, plane, elbow flexion toward `bend` (chest frame). */
  void armAngles (int s, double elevation, double plane, double flexion, const Eigen::Vector3d &bend_chest,
                  const Eigen::Vector3d &palm_chest)
  {
    const double sigma = s == 0 ? 1.0 : -1.0;
    const double e = elevation * kDeg, p = plane * kDeg;
    const Eigen::Vector3d d =
        chest_ * Eigen::Vector3d (sigma * std::sin (e) * std::cos (p), -std::cos (e), std::sin (e) * std::sin (p));
    Eigen::Vector3d b = across (chest_ * bend_chest, d);
    if (b.norm () < 1e-6)
      b = across (chest_ * Eigen::Vector3d::UnitZ (), d);
    if (b.norm () < 1e-6)
      b = across (chest_ * Eigen::Vector3d::UnitY (), d);
    const Eigen::Vector3d f = std::cos (flexion * kDeg) * d + std::sin (flexion * kDeg) * b.normalized ();
    t_.elbow[s] = t_.shoulder[s] + kUpperArm * d;
    t_.wrist[s] = t_.elbow[s] + kForearm * f;
    t_.hand_end[s] = t_.wrist[s] + kHand * f;
    t_.palm_across[s] = chest_ * palm_chest;
  }

  /** An arm reaching a wrist target (two-bone solution), the elbow toward `elbow_hint`
    * (chest frame); the hand continues the forearm unless hand_dir is given. */
  void armTarget (int s, const Eigen::Vector3d &target, const Eigen::Vector3d &elbow_hint,
                  const Eigen::Vector3d &hand_dir = Eigen::Vector3d::Zero ())
  {
    const Eigen::Vector3d S = t_.shoulder[s];
    Eigen::Vector3d w = target - S;
    const double reach = std::clamp (w.norm (), kUpperArm - kForearm + 0.02, kUpperArm + kForearm - 0.002);
    w = w.normalized ();
    const double cos_a = (kUpperArm * kUpperArm + reach * reach - kForearm * kForearm) / (2 * kUpperArm * reach);
    Eigen::Vector3d e = across (chest_ * elbow_hint, w);
    if (e.norm () < 1e-6)
      e = across (chest_ * Eigen::Vector3d (0, -1, 0), w);
    e.normalize ();
    t_.elbow[s] = S + kUpperArm * (cos_a * w + std::sqrt (std::max (0.0, 1 - cos_a * cos_a)) * e);
    t_.wrist[s] = S + reach * w;
    const Eigen::Vector3d f = (t_.wrist[s] - t_.elbow[s]).normalized ();
    t_.hand_end[s] = t_.wrist[s] + kHand * (hand_dir.norm () > 0 ? Eigen::Vector3d (chest_ * hand_dir.normalized ()) : f);
    t_.palm_across[s] = chest_ * Eigen::Vector3d (0, 1, 0.3);
  }

  /** A leg from hip flexion and abduction, knee flexion; the foot level unless `ankle` given. */
  void leg (int s, double hip_flexion, double abduction, double knee, double ankle_extra = 0.0)
  {
    const double sigma = s == 0 ? 1.0 : -1.0;
    const Eigen::Matrix3d thigh = pelvis_ * rz (sigma * abduction) * rx (-hip_flexion);
    const Eigen::Matrix3d shin = thigh * rx (knee);
    const Eigen::Matrix3d foot = shin * rx (hip_flexion - knee + ankle_extra);
    const int j = s == 0 ? PoseSkeleton::LeftUpLeg : PoseSkeleton::RightUpLeg;
    t_.knee[s] = t_.hip[s] + thigh * PoseSkeleton::offset (j + 1);
    t_.ankle[s] = t_.knee[s] + shin * PoseSkeleton::offset (j + 2);
    t_.toe[s] = t_.ankle[s] + foot * PoseSkeleton::offset (j + 3);
  }

  PoseTargets &targets () { return t_; }
  const Eigen::Matrix3d &chest () const { return chest_; }
  const Eigen::Matrix3d &pelvis () const { return pelvis_; }

private:
  SynthRng &rng_;
  PoseTargets t_;
  Eigen::Matrix3d pelvis_ = Eigen::Matrix3d::Identity (), chest_ = Eigen::Matrix3d::Identity ();
};
}  // namespace

const char *
armPoseName (ArmPose pose)
{
  static const char *names[] = {"relaxed",      "hands-on-hips",    "hands-in-pockets", "crossed-arms",
                                "hands-behind-back", "one-arm-raised", "both-arms-raised", "pointing-forward",
                                "hand-near-face", "waving",           "reaching-sideways"};
  const int i = static_cast<int> (pose);
  return i >= 0 && i < static_cast<int> (ArmPose::kCount) ? names[i] : "unknown";
}

const char *
legPoseName (LegPose pose)
{
  static const char *names[] = {"standing", "stepping", "kneeling", "seated"};
  const int i = static_cast<int> (pose);
  return i >= 0 && i < static_cast<int> (LegPose::kCount) ? names[i] : "unknown";
}

const std::vector<JointLimit> &
ProceduralPoses::jointLimits ()
{
  // Ranges of motion of healthy adults (rounded, after the AAOS tables), narrowed where
  // a pose in front of a camera has no use for the extremes.
  static const std::vector<JointLimit> limits = {
      {"trunk", "flexion (+ forward)", -20, 50},
      {"trunk", "lateral bend", -20, 20},
      {"trunk", "twist", -35, 35},
      {"head", "yaw", -70, 70},
      {"head", "pitch (+ down)", -40, 50},
      {"shoulder", "elevation (0 hanging, 180 up)", 0, 180},
      {"shoulder", "plane (0 side, 90 forward; above 30 elevation)", -90, 140},
      {"elbow", "flexion", 0, 150},
      {"hip", "flexion (+ forward)", -25, 125},
      {"hip", "abduction", -15, 45},
      {"knee", "flexion", 0, 150},
  };
  return limits;
}

PoseAngles
ProceduralPoses::measure (const PoseFrame &pose)
{
  PoseAngles a;
  const std::vector<Eigen::Vector3d> p = PoseSkeleton::positions (pose);
  auto global = [&] (int joint) {
    Eigen::Matrix3d g = Eigen::Matrix3d::Identity ();
    std::vector<int> chain;
    for (int j = joint; j >= 0; j = PoseSkeleton::parent (j))
      chain.push_back (j);
    for (auto it = chain.rbegin (); it != chain.rend (); ++it)
      g = g * (static_cast<std::size_t> (*it) < pose.local.size () ? pose.local[*it] : Eigen::Matrix3d::Identity ());
    return g;
  };
  const Eigen::Matrix3d pelvis = global (PoseSkeleton::Hips), chest = global (PoseSkeleton::Spine1);
  const Eigen::Vector3d up = pelvis.transpose () * chest.col (1), left = pelvis.transpose () * chest.col (0);
  a.trunk_flexion = std::atan2 (up.z (), up.y ()) / kDeg;
  a.trunk_lateral = std::atan2 (up.x (), up.y ()) / kDeg;
  a.trunk_twist = std::atan2 (-left.z (), left.x ()) / kDeg;
  const Eigen::Vector3d face = chest.transpose () * global (PoseSkeleton::Head).col (2);
  a.head_yaw = std::atan2 (face.x (), face.z ()) / kDeg;
  a.head_pitch = std::atan2 (-face.y (), std::hypot (face.x (), face.z ())) / kDeg;
  for (int s = 0; s < 2; ++s)
  {
    const double sigma = s == 0 ? 1.0 : -1.0;
    const int arm = s == 0 ? PoseSkeleton::LeftArm : PoseSkeleton::RightArm;
    const Eigen::Vector3d d = (chest.transpose () * (p[arm + 1] - p[arm])).normalized ();
    a.shoulder_elevation[s] = std::acos (std::clamp (-d.y (), -1.0, 1.0)) / kDeg;
    a.shoulder_plane[s] = std::atan2 (d.z (), sigma * d.x ()) / kDeg;
    a.elbow_flexion[s] = angleBetween (p[arm + 1] - p[arm], p[arm + 2] - p[arm + 1]);
    const int leg = s == 0 ? PoseSkeleton::LeftUpLeg : PoseSkeleton::RightUpLeg;
    const Eigen::Vector3d t = (pelvis.transpose () * (p[leg + 1] - p[leg])).normalized ();
    a.hip_flexion[s] = std::atan2 (t.z (), -t.y ()) / kDeg;
    a.hip_abduction[s] = std::asin (std::clamp (sigma * t.x (), -1.0, 1.0)) / kDeg;
    a.knee_flexion[s] = angleBetween (p[leg + 1] - p[leg], p[leg + 2] - p[leg + 1]);
  }
  return a;
}

std::vector<std::string>
ProceduralPoses::violations (const PoseAngles &a)
{
  std::vector<std::string> out;
  const auto &l = jointLimits ();
  auto check = [&] (std::size_t limit, double value, const char *side) {
    // Half a degree of slack: the angles are measured back from a BVH's rounded channels.
    if (!(value >= l[limit].min_degrees - 0.5 && value <= l[limit].max_degrees + 0.5))
      out.push_back (std::string (side) + l[limit].joint + " " + l[limit].motion + " " + std::to_string (value));
  };
  check (0, a.trunk_flexion, "");
  check (1, a.trunk_lateral, "");
  check (2, a.trunk_twist, "");
  check (3, a.head_yaw, "");
  check (4, a.head_pitch, "");
  for (int s = 0; s < 2; ++s)
  {
    const char *side = s == 0 ? "left " : "right ";
    check (5, a.shoulder_elevation[s], side);
    if (a.shoulder_elevation[s] > 30)
      check (6, a.shoulder_plane[s], side);
    check (7, a.elbow_flexion[s], side);
    check (8, a.hip_flexion[s], side);
    check (9, a.hip_abduction[s], side);
    check (10, a.knee_flexion[s], side);
  }
  return out;
}

ProceduralPose
ProceduralPoses::make (ArmPose arms, LegPose legs, SynthRng &rng)
{
  ProceduralPose result;
  result.arms = arms;
  result.legs = legs;
  const Eigen::Vector3d forward (0, 0, 1), up (0, 1, 0);
  // Up to 20 draws: target-reaching arms may need an elbow out of range for an odd torso.
  for (int attempt = 0; attempt < 20; ++attempt)
  {
    PoseBuilder b (rng);
    const bool seated = legs == LegPose::Seated;
    b.torso (b.u (-5, seated ? 25 : 15), b.u (-8, 8), b.u (-20, 20), b.u (-50, 50), b.u (-25, 30));
    PoseTargets &t = b.targets ();
    const int side = rng.index (2);  // the one arm / the leading leg
    auto relaxed = [&] (int s) { b.armAngles (s, b.u (5, 25), b.u (0, 60), b.u (5, 40), forward, forward); };
    auto raised = [&] (int s) { b.armAngles (s, b.u (145, 178), b.u (0, 90), b.u (0, 30), forward, forward); };
    const Eigen::Matrix3d &c = b.chest ();
    const Eigen::Matrix3d &pv = b.pelvis ();
    auto jitter = [&] (double r) { return Eigen::Vector3d (b.u (-r, r), b.u (-r, r), b.u (-r, r)); };
    for (int s = 0; s < 2; ++s)
    {
      const double sigma = s == 0 ? 1.0 : -1.0;
      switch (arms)
      {
        case ArmPose::Relaxed: relaxed (s); break;
        case ArmPose::HandsOnHips:
          if (s == side || rng.chance (0.6))
            b.armTarget (s, t.root + pv * Eigen::Vector3d (sigma * 0.16, 0.05, 0.0) + jitter (0.025),
                         Eigen::Vector3d (sigma, 0, -0.4));
          else
            relaxed (s);
          break;
        case ArmPose::HandsInPockets:
          b.armTarget (s, t.hip[s] + pv * Eigen::Vector3d (sigma * 0.06, -0.08, rng.chance (0.7) ? 0.08 : -0.10) + jitter (0.02),
                       Eigen::Vector3d (sigma * 0.6, 0, -1), Eigen::Vector3d (0, -1, 0));
          break;
        case ArmPose::CrossedArms:
          b.armTarget (s, t.chest + c * Eigen::Vector3d (-sigma * 0.12, -0.11 + 0.02 * s, 0.14 + 0.03 * s) + jitter (0.02),
                       Eigen::Vector3d (sigma * 0.3, -1, 0.4), c.transpose () * Eigen::Vector3d (-sigma, 0, 0));
          break;
        case ArmPose::HandsBehindBack:
          b.armTarget (s, t.root + pv * Eigen::Vector3d (sigma * 0.05, 0.04, -0.17) + jitter (0.02),
                       Eigen::Vector3d (sigma, 0, -0.3));
          break;
        case ArmPose::OneArmRaised:
          if (s == side)
            raised (s);
          else
            relaxed (s);
          break;
        case ArmPose::BothArmsRaised: raised (s); break;
        case ArmPose::PointingForward:
          if (s == 1)
            b.armAngles (s, b.u (80, 100), b.u (82, 98), b.u (0, 8), forward, up);
          else
            relaxed (s);
          break;
        case ArmPose::HandNearFace:
          if (s == side)
          {
            const Eigen::Matrix3d head = t.head_rotation;
            b.armTarget (s, t.head + head * Eigen::Vector3d (sigma * 0.07, -0.08, 0.10) + jitter (0.025),
                         Eigen::Vector3d (sigma * 0.5, -1, 0.3), Eigen::Vector3d (0, 1, 0));
          }
          else
            relaxed (s);
          break;
        case ArmPose::Waving:
          if (s == side)
            b.armAngles (s, b.u (60, 100), b.u (0, 50), b.u (60, 115), up, forward);
          else
            relaxed (s);
          break;
        case ArmPose::ReachingSideways:
          if (s == side)
            b.armAngles (s, b.u (70, 110), b.u (-15, 25), b.u (0, 20), forward, up);
          else
            relaxed (s);
          break;
        default: relaxed (s); break;
      }
      const double sgn = s == side ? 1.0 : -1.0;
      switch (legs)
      {
        case LegPose::Standing: b.leg (s, b.u (-5, 5), b.u (0, 10), b.u (0, 10)); break;
        case LegPose::Stepping:
          if (sgn > 0)
            b.leg (s, b.u (10, 35), b.u (0, 8), b.u (5, 35));
          else
            b.leg (s, b.u (-20, -5), b.u (0, 8), b.u (0, 25));
          break;
        case LegPose::Kneeling:
          if (sgn > 0)  // the knee on the ground, toes tucked behind
            b.leg (s, b.u (-5, 10), b.u (0, 10), b.u (85, 100), b.u (-60, -40));
          else  // the foot in front, or both knees down
            rng.chance (0.3) ? b.leg (s, b.u (-5, 10), b.u (0, 10), b.u (85, 100), b.u (-60, -40))
                             : b.leg (s, b.u (75, 100), b.u (0, 15), b.u (75, 100));
          break;
        case LegPose::Seated: b.leg (s, b.u (75, 100), b.u (0, 20), b.u (70, 110)); break;
        default: b.leg (s, 0, 0, 0); break;
      }
    }
    result.frame = PoseSkeleton::solvePose (t, 1.0);
    if (violations (measure (result.frame)).empty ())
      return result;
  }
  return result;  // the last draw; generate() drops poses that still break a limit
}

std::vector<ProceduralPose>
ProceduralPoses::generate (int count, std::uint64_t seed)
{
  if (count < 0 || count > 100000)
    throw std::invalid_argument ("procedural poses: count must be 0-100000, got " + std::to_string (count));
  std::vector<ProceduralPose> poses;
  const int arm_kinds = static_cast<int> (ArmPose::kCount), leg_kinds = static_cast<int> (LegPose::kCount);
  for (int i = 0; i < count; ++i)
  {
    SynthRng rng = SynthRng::forItem (seed, static_cast<std::uint64_t> (i));
    const auto arms = static_cast<ArmPose> (i % arm_kinds);
    // Legs: standing half the time, the rest split between stepping, kneeling and seated.
    const int leg_draw = rng.index (6);
    const auto legs = static_cast<LegPose> (leg_draw < 3 ? 0 : leg_draw - 2);
    (void) leg_kinds;
    ProceduralPose pose = make (arms, legs, rng);
    if (violations (measure (pose.frame)).empty ())
      poses.push_back (std::move (pose));
  }
  return poses;
}
}  // namespace agex
