#include <agex/simulation/pose_skeleton.h>

#include <cmath>
#include <cstdio>
#include <sstream>

namespace agex
{
namespace
{
struct JointDef
{
  const char *name;
  int parent;
  double x, y, z;
};

// A 1.75 m adult in a T-pose: hips 0.90 m up, thigh 0.42, shin 0.40, upper arm 0.29,
// forearm 0.26, wrist to finger tip 0.18; the top of the head is the Head End Site.
const JointDef kJointDefs[PoseSkeleton::kJoints] = {
    {"Hips", -1, 0.0, 0.90, 0.0},
    {"LeftUpLeg", 0, 0.09, -0.02, 0.0},
    {"LeftLeg", 1, 0.0, -0.42, 0.0},
    {"LeftFoot", 2, 0.0, -0.40, 0.0},
    {"LeftToeBase", 3, 0.0, -0.055, 0.13},
    {"RightUpLeg", 0, -0.09, -0.02, 0.0},
    {"RightLeg", 5, 0.0, -0.42, 0.0},
    {"RightFoot", 6, 0.0, -0.40, 0.0},
    {"RightToeBase", 7, 0.0, -0.055, 0.13},
    {"LowerBack", 0, 0.0, 0.08, 0.0},
    {"Spine", 9, 0.0, 0.12, 0.0},
    {"Spine1", 10, 0.0, 0.14, 0.0},
    {"Neck", 11, 0.0, 0.18, 0.0},
    {"Head", 12, 0.0, 0.10, 0.0},
    {"LeftArm", 11, 0.18, 0.14, 0.0},
    {"LeftForeArm", 14, 0.29, 0.0, 0.0},
    {"LeftHand", 15, 0.26, 0.0, 0.0},
    {"LeftHandIndex1", 16, 0.10, 0.0, 0.0},
    {"RightArm", 11, -0.18, 0.14, 0.0},
    {"RightForeArm", 18, -0.29, 0.0, 0.0},
    {"RightHand", 19, -0.26, 0.0, 0.0},
    {"RightHandIndex1", 20, -0.10, 0.0, 0.0},
};
// End Sites: head top, toe ends, finger tips.
const Eigen::Vector3d kHeadEnd (0.0, 0.20, 0.0), kToeEnd (0.0, 0.0, 0.06), kFingerEnd (0.08, 0.0, 0.0);

Eigen::Matrix3d
frameOf (const Eigen::Vector3d &left_in, const Eigen::Vector3d &up_in, const Eigen::Matrix3d &fallback)
{
  if (left_in.norm () < 1e-12 || up_in.norm () < 1e-12)
    return fallback;
  const Eigen::Vector3d left = left_in.normalized ();
  Eigen::Vector3d up = up_in - up_in.dot (left) * left;
  if (up.norm () < 1e-9 * up_in.norm ())
    return fallback;
  up.normalize ();
  Eigen::Matrix3d m;
  m << left, up, left.cross (up);
  return m;
}

Eigen::Matrix3d
slerp (const Eigen::Matrix3d &a, const Eigen::Matrix3d &b, double t)
{
  return Eigen::Quaterniond (a).slerp (t, Eigen::Quaterniond (b)).toRotationMatrix ();
}

double
smoothstep (double lo, double hi, double x)
{
  const double t = std::min (1.0, std::max (0.0, (x - lo) / (hi - lo)));
  return t * t * (3.0 - 2.0 * t);
}

/** A limb's upper segment (arm or thigh): swung from the parent, then twisted so that
  * the rest axis `rest_bend` points along the middle joint's bend; for a nearly straight
  * limb, along `straight_hint` (palm or foot), both taken across the segment. */
Eigen::Matrix3d
upperSegment (const Eigen::Matrix3d &parent, const Eigen::Vector3d &rest_dir, const Eigen::Vector3d &rest_bend,
              const Eigen::Vector3d &upper, const Eigen::Vector3d &lower, double bend_sign,
              const Eigen::Vector3d &straight_hint)
{
  const Eigen::Matrix3d swung = swingFrom (parent, rest_dir, upper);
  if (upper.norm () < 1e-12)
    return swung;
  const Eigen::Vector3d u = upper.normalized ();
  auto across = [&] (const Eigen::Vector3d &v) -> Eigen::Vector3d { return v - v.dot (u) * u; };
  auto twisted = [&] (const Eigen::Vector3d &want) -> Eigen::Matrix3d {
    const Eigen::Vector3d now = across (swung * rest_bend);
    if (want.norm () < 1e-9 || now.norm () < 1e-9)
      return swung;
    const double angle = std::atan2 (now.cross (want).dot (u), now.dot (want));
    return Eigen::AngleAxisd (angle, u).toRotationMatrix () * swung;
  };
  const Eigen::Vector3d lower_dir = lower.norm () > 1e-12 ? Eigen::Vector3d (lower.normalized ()) : u;
  const Eigen::Vector3d bend = across (lower_dir) * bend_sign;
  const Eigen::Matrix3d by_bend = twisted (bend);
  const Eigen::Matrix3d by_hint = twisted (across (straight_hint));
  // sin of the bend: below ~10 degrees the bend's plane is noise, above ~25 it is clear.
  return slerp (by_hint, by_bend, smoothstep (0.17, 0.42, bend.norm ()));
}

/** Twists `frame` about `axis` so that its `rest_across` points along `want` (across the axis). */
Eigen::Matrix3d
twistToward (const Eigen::Matrix3d &frame, const Eigen::Vector3d &axis_in, const Eigen::Vector3d &rest_across,
             const Eigen::Vector3d &want_in)
{
  if (axis_in.norm () < 1e-12)
    return frame;
  const Eigen::Vector3d axis = axis_in.normalized ();
  const Eigen::Vector3d now = frame * rest_across - (frame * rest_across).dot (axis) * axis;
  const Eigen::Vector3d want = want_in - want_in.dot (axis) * axis;
  if (now.norm () < 1e-9 || want.norm () < 1e-9)
    return frame;
  const double angle = std::atan2 (now.cross (want).dot (axis), now.dot (want));
  return Eigen::AngleAxisd (angle, axis).toRotationMatrix () * frame;
}
}  // namespace

Eigen::Matrix3d
swingFrom (const Eigen::Matrix3d &parent, const Eigen::Vector3d &rest_direction, const Eigen::Vector3d &target)
{
  const Eigen::Vector3d now = parent * rest_direction;
  if (target.norm () < 1e-12 || now.norm () < 1e-12)
    return parent;
  return Eigen::Quaterniond::FromTwoVectors (now, target).toRotationMatrix () * parent;
}

const char *
PoseSkeleton::jointName (int joint)
{
  return joint >= 0 && joint < kJoints ? kJointDefs[joint].name : "unknown";
}

int
PoseSkeleton::parent (int joint)
{
  return joint >= 0 && joint < kJoints ? kJointDefs[joint].parent : -1;
}

Eigen::Vector3d
PoseSkeleton::offset (int joint)
{
  if (joint < 0 || joint >= kJoints)
    return Eigen::Vector3d::Zero ();
  const JointDef &d = kJointDefs[joint];
  return Eigen::Vector3d (d.x, d.y, d.z);
}

double
PoseSkeleton::standingHeight ()
{
  // Soles at 0 (the ankle 0.08 m up), hips 0.90, back 0.34, neck and head 0.28, to the head's End Site.
  return 0.90 + 0.08 + 0.12 + 0.14 + 0.18 + 0.10 + kHeadEnd.y ();
}

double
PoseSkeleton::legLength ()
{
  return 0.42 + 0.40;
}

std::vector<Eigen::Vector3d>
PoseSkeleton::positions (const PoseFrame &pose)
{
  std::vector<Eigen::Vector3d> p (kJoints);
  std::vector<Eigen::Matrix3d> g (kJoints);
  for (int j = 0; j < kJoints; ++j)
  {
    const Eigen::Matrix3d local = j < static_cast<int> (pose.local.size ()) ? pose.local[j] : Eigen::Matrix3d::Identity ();
    const int par = parent (j);
    if (par < 0)
    {
      g[j] = local;
      p[j] = pose.root;
    }
    else
    {
      g[j] = g[par] * local;
      p[j] = p[par] + g[par] * offset (j);
    }
  }
  return p;
}

PoseFrame
PoseSkeleton::solvePose (const PoseTargets &t, double root_scale)
{
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX (), Y = Eigen::Vector3d::UnitY (), Z = Eigen::Vector3d::UnitZ ();
  std::vector<Eigen::Matrix3d> g (kJoints, Eigen::Matrix3d::Identity ());
  const Eigen::Vector3d hips_mid = 0.5 * (t.hip[0] + t.hip[1]);
  g[Hips] = frameOf (t.hip[0] - t.hip[1], t.chest - hips_mid, Eigen::Matrix3d::Identity ());
  const Eigen::Matrix3d chest = frameOf (t.shoulder[0] - t.shoulder[1], t.neck - t.chest, g[Hips]);
  // The back bends over three joints; each takes a third of the pelvis-to-chest turn.
  g[LowerBack] = slerp (g[Hips], chest, 1.0 / 3.0);
  g[Spine] = slerp (g[Hips], chest, 2.0 / 3.0);
  g[Spine1] = chest;
  g[Neck] = swingFrom (chest, Y, t.head - t.neck);
  g[Head] = t.head_rotation;

  for (int side = 0; side < 2; ++side)
  {
    const double sigma = side == 0 ? 1.0 : -1.0;
    const int arm = side == 0 ? LeftArm : RightArm;
    const Eigen::Vector3d along = sigma * X;
    // Elbow flexion from the T-pose (palms down) swings the forearm forward (+Z).
    const Eigen::Vector3d upper = t.elbow[side] - t.shoulder[side], fore = t.wrist[side] - t.elbow[side];
    g[arm] = upperSegment (chest, along, Z, upper, fore, 1.0, t.palm_across[side]);
    g[arm + 1] = twistToward (swingFrom (g[arm], along, fore), fore, Z, t.palm_across[side]);
    g[arm + 2] = swingFrom (g[arm + 1], along, t.hand_end[side] - t.wrist[side]);
    g[arm + 3] = g[arm + 2];

    const int leg = side == 0 ? LeftUpLeg : RightUpLeg;
    const Eigen::Vector3d thigh = t.knee[side] - t.hip[side], shin = t.ankle[side] - t.knee[side];
    const Eigen::Vector3d foot = t.toe[side] - t.ankle[side];
    // Knee flexion swings the shin backward (-Z); a straight leg takes its twist from the foot.
    g[leg] = upperSegment (g[Hips], -Y, Z, thigh, shin, -1.0, foot);
    g[leg + 1] = swingFrom (g[leg], -Y, shin);
    g[leg + 2] = swingFrom (g[leg + 1], offset (leg + 3).normalized (), foot);
    g[leg + 3] = g[leg + 2];
  }

  PoseFrame pose;
  pose.root = t.root * root_scale;
  pose.local.resize (kJoints);
  for (int j = 0; j < kJoints; ++j)
  {
    const int par = parent (j);
    pose.local[j] = par < 0 ? g[j] : Eigen::Matrix3d (g[par].transpose () * g[j]);
  }
  return pose;
}

BvhMotion
PoseSkeleton::motion (const std::vector<PoseFrame> &poses, const std::string &name)
{
  if (poses.empty ())
    throw BvhError (name + ": no poses to make a motion of");
  std::ostringstream out;
  char buffer[128];
  auto vec = [&] (const Eigen::Vector3d &v) {
    std::snprintf (buffer, sizeof buffer, "%.6f %.6f %.6f", v.x (), v.y (), v.z ());
    return std::string (buffer);
  };
  out << "HIERARCHY\n";
  // Children in joint order; End Sites after the joints that have them.
  auto emit = [&] (auto &self, int j, int depth) -> void {
    const std::string pad (static_cast<std::size_t> (depth), ' ');
    out << pad << (j == 0 ? "ROOT " : "JOINT ") << jointName (j) << "\n" << pad << "{\n";
    out << pad << "  OFFSET " << vec (offset (j)) << "\n";
    out << pad << "  CHANNELS " << (j == 0 ? "6 Xposition Yposition Zposition " : "3 ")
        << "Zrotation Xrotation Yrotation\n";
    bool child = false;
    for (int c = 0; c < kJoints; ++c)
      if (parent (c) == j)
      {
        self (self, c, depth + 2);
        child = true;
      }
    if (!child)
    {
      const Eigen::Vector3d end = j == Head ? kHeadEnd
                                  : (j == LeftToeBase || j == RightToeBase) ? kToeEnd
                                  : j == LeftHandIndex1                      ? kFingerEnd
                                                                             : Eigen::Vector3d (-kFingerEnd);
      out << pad << "  End Site\n" << pad << "  {\n" << pad << "    OFFSET " << vec (end) << "\n" << pad << "  }\n";
    }
    out << pad << "}\n";
  };
  emit (emit, 0, 0);
  out << "MOTION\nFrames: " << poses.size () << "\nFrame Time: 0.033333\n";
  for (const PoseFrame &p : poses)
  {
    out << vec (p.root);
    for (int j = 0; j < kJoints; ++j)
    {
      const Eigen::Matrix3d r = j < static_cast<int> (p.local.size ()) ? p.local[j] : Eigen::Matrix3d::Identity ();
      // R = Rz(a) Rx(b) Ry(c), the order of the channels.
      const Eigen::Vector3d e = r.eulerAngles (2, 0, 1) * (180.0 / M_PI);
      if (!e.allFinite () || !p.root.allFinite ())
        throw BvhError (name + ": a pose has a rotation or position that is not finite");
      out << " " << vec (e);
    }
    out << "\n";
  }
  return BvhMotion::parse (out.str (), name);
}
}  // namespace agex
