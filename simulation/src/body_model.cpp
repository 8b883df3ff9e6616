// The capsule-and-ellipsoid body posed by a clip.
#include <agex/simulation/body_model.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace agex
{
namespace
{
constexpr double kInf = std::numeric_limits<double>::infinity ();

std::string
fixed (double v, int digits = 3)
{
  std::ostringstream out;
  out << std::fixed << std::setprecision (digits) << v;
  return out.str ();
}

/** Orthonormal basis with `axis` as the second column. */
Eigen::Matrix3d
basisAlong (const Eigen::Vector3d &axis, const Eigen::Vector3d &hint)
{
  const Eigen::Vector3d y = axis.norm () > 1e-12 ? Eigen::Vector3d (axis.normalized ()) : Eigen::Vector3d::UnitY ();
  Eigen::Vector3d z = hint - hint.dot (y) * y;
  if (z.norm () < 1e-6)
    z = y.unitOrthogonal ();
  z.normalize ();
  const Eigen::Vector3d x = y.cross (z);
  Eigen::Matrix3d m;
  m << x, y, z;
  return m;
}


}  // namespace

BodyParams
BodyParams::random (SynthRng &rng)
{
  BodyParams p;
  p.height_scale = rng.uniform (0.92, 1.08);
  p.girth = rng.uniform (0.85, 1.25);
  p.head_scale = rng.uniform (0.93, 1.07);
  p.arm_girth = rng.uniform (0.9, 1.12);
  p.leg_girth = rng.uniform (0.9, 1.12);
  p.torso_depth = rng.uniform (0.9, 1.2);
  p.reflectivity = rng.uniform (0.45, 0.9);
  return p;
}

void
BodyParams::dress (SynthRng &rng)
{
  clothes_top = rng.uniform (0.003, 0.025);
  clothes_bottom = rng.uniform (0.003, 0.025);
  shoes = rng.uniform (0.008, 0.025);
  hands = rng.uniform (0.002, 0.01);
  hair = rng.uniform (0.0, 0.03);
}

std::string
BodyParams::describe () const
{
  std::string text = "height_scale=" + fixed (height_scale) + " girth=" + fixed (girth) +
                     " head_scale=" + fixed (head_scale) + " arm_girth=" + fixed (arm_girth) +
                     " leg_girth=" + fixed (leg_girth) + " torso_depth=" + fixed (torso_depth) +
                     " reflectivity=" + fixed (reflectivity, 2);
  if (dressed ())
    text += " clothes_top=" + fixed (clothes_top) + " clothes_bottom=" + fixed (clothes_bottom) +
            " shoes=" + fixed (shoes) + " hands=" + fixed (hands) + " hair=" + fixed (hair);
  return text;
}

BodyModel
BodyModel::transformed (const Eigen::Isometry3d &t) const
{
  BodyModel b = *this;
  for (auto &p : b.primitives)
    p = p.transformed (t);
  for (int i = 0; i < 5; ++i)
  {
    b.tip[i] = t * tip[i];
    b.base[i] = t * base[i];
  }
  b.centre = t * centre;
  return b;
}

BodyModel
buildBody (const MotionClip &clip, int frame, const BodyParams &bp)
{
  const SkeletonMap &m = clip.map;
  const double s = bp.height_scale;
  std::vector<Eigen::Isometry3d> g;
  clip.motion.pose (frame, clip.scale * s, g);
  auto P = [&] (int j) -> Eigen::Vector3d { return g[j].translation (); };
  // Posed (left, up, forward) of the segment a joint rotates.
  auto B = [&] (int j) -> Eigen::Matrix3d { return g[j].linear () * m.rest_basis; };
  const float refl = static_cast<float> (bp.reflectivity);
  const double girth = s * bp.girth;

  BodyModel body;
  SynthMaterial material = SynthMaterial::Skin;  // of the primitives added next
  SynthPart part = SynthPart::Head;              // likewise
  auto add = [&] (SynthPrimitive p) {
    p.reflectivity = refl;
    p.material = material;
    p.part = part;
    body.primitives.push_back (p);
  };
  // Side 0 is the subject's left.
  auto sided = [] (int side, SynthPart left, SynthPart right) { return side == 0 ? left : right; };
  auto capsule = [&] (const Eigen::Vector3d &a, const Eigen::Vector3d &b, double r) {
    add (SynthPrimitive::capsule (a, b, r, SynthObject::Person));
  };
  auto ellipsoid = [&] (const Eigen::Vector3d &c, const Eigen::Matrix3d &basis, const Eigen::Vector3d &semi) {
    add (SynthPrimitive::ellipsoid (c, basis * semi.asDiagonal (), SynthObject::Person));
  };

  // Head: an ellipsoid on the head joint; its top is the head tip, the head joint (top
  // of the neck) the base.
  {
    const Eigen::Matrix3d hb = B (m.head);
    const double hs = s * bp.head_scale;
    const Eigen::Vector3d semi = Eigen::Vector3d (0.078, 0.108, 0.095) * hs;
    const Eigen::Vector3d c = P (m.head) + hb * Eigen::Vector3d (0.0, 0.09, 0.015) * hs;
    body.tip_primitives[0] = {static_cast<int> (body.primitives.size ())};
    body.tip_tolerance[0] = std::max (semi.x (), semi.z ()) + 0.03;
    ellipsoid (c, hb, semi);
    body.tip[0] = c + hb.col (1) * semi.y ();
    body.base[0] = P (m.head);
  }
  part = SynthPart::Neck;
  capsule (P (m.neck), P (m.head), 0.052 * girth);
  // Torso: chest, abdomen and pelvis ellipsoids, a capsule across the shoulders.
  const double td = bp.torso_depth;
  material = SynthMaterial::Top;
  part = SynthPart::Torso;
  {
    const Eigen::Matrix3d cb = B (m.spine_mid);
    const Eigen::Vector3d c = 0.5 * (P (m.spine_mid) + P (m.neck)) + cb * Eigen::Vector3d (0, 0.01, -0.01) * s;
    ellipsoid (c, cb, Eigen::Vector3d (0.165 * girth, 0.18 * s, 0.11 * girth * td));
  }
  {
    const Eigen::Matrix3d ab = B (m.spine_base);
    const Eigen::Vector3d c = P (m.spine_base) + 0.55 * (P (m.spine_mid) - P (m.spine_base));
    ellipsoid (c, ab, Eigen::Vector3d (0.145 * girth, 0.12 * s, 0.10 * girth * td));
  }
  {
    const Eigen::Matrix3d pb = B (m.root);
    const Eigen::Vector3d c = P (m.root) + pb * Eigen::Vector3d (0, -0.045, -0.01) * s;
    part = SynthPart::Pelvis;
    ellipsoid (c, pb, Eigen::Vector3d (0.16 * girth, 0.11 * s, 0.11 * girth * td));
  }
  part = SynthPart::Torso;
  capsule (P (m.shoulder[0]), P (m.shoulder[1]), 0.055 * girth);

  for (int side = 0; side < 2; ++side)
  {
    // Arms and hands.
    const double arm = girth * bp.arm_girth;
    const Eigen::Vector3d sh = P (m.shoulder[side]), el = P (m.elbow[side]), wr = P (m.wrist[side]);
    material = SynthMaterial::Top;
    part = sided (side, SynthPart::LeftUpperArm, SynthPart::RightUpperArm);
    capsule (sh, el, 0.047 * arm);
    part = sided (side, SynthPart::LeftForearm, SynthPart::RightForearm);
    capsule (el, wr, 0.038 * arm);
    Eigen::Vector3d hand_dir = wr - el;
    if (m.hand_end[side] >= 0 && (P (m.hand_end[side]) - wr).norm () > 0.01 * s)
      hand_dir = P (m.hand_end[side]) - wr;
    if (hand_dir.norm () < 1e-9)  // a degenerate skeleton: hang the hand down
      hand_dir = -B (m.wrist[side]).col (1);
    hand_dir.normalize ();
    const double hand_r = 0.03 * s * (0.5 + 0.5 * bp.girth);
    const double hand_len = 0.12 * s;
    body.tip_primitives[1 + side] = {static_cast<int> (body.primitives.size ())};
    body.tip_tolerance[1 + side] = hand_r + 0.03;
    material = SynthMaterial::Skin;
    part = sided (side, SynthPart::LeftHand, SynthPart::RightHand);
    capsule (wr + hand_dir * 0.02 * s, wr + hand_dir * hand_len, hand_r);
    body.tip[1 + side] = wr + hand_dir * (hand_len + hand_r);
    body.base[1 + side] = wr;

    // Legs: capsules with a thigh and a calf ellipsoid for the taper.
    const double leg = girth * bp.leg_girth;
    const Eigen::Vector3d hp = P (m.hip[side]), kn = P (m.knee[side]), an = P (m.ankle[side]);
    material = SynthMaterial::Bottom;
    const SynthPart thigh = sided (side, SynthPart::LeftThigh, SynthPart::RightThigh);
    const SynthPart lower_leg = sided (side, SynthPart::LeftLowerLeg, SynthPart::RightLowerLeg);
    part = thigh;
    capsule (hp, kn, 0.06 * leg);
    part = lower_leg;
    capsule (kn, an, 0.045 * leg);
    {
      const double len = (kn - hp).norm ();
      const Eigen::Matrix3d lb = basisAlong (kn - hp, B (m.hip[side]).col (2));
      part = thigh;
      ellipsoid (hp + 0.4 * (kn - hp), lb, Eigen::Vector3d (0.08 * leg, 0.55 * len, 0.08 * leg));
    }
    {
      part = lower_leg;
      const double len = (an - kn).norm ();
      const Eigen::Matrix3d lb = basisAlong (an - kn, B (m.knee[side]).col (2));
      ellipsoid (kn + 0.35 * (an - kn) - lb.col (2) * 0.012 * s, lb, Eigen::Vector3d (0.056 * leg, 0.4 * len, 0.058 * leg));
    }
    // Foot: heel to the ball, the ball to the toe end.
    const Eigen::Matrix3d fb = B (m.ankle[side]);
    const Eigen::Vector3d heel = an + fb * Eigen::Vector3d (0, -0.035, -0.035) * s;
    Eigen::Vector3d ball, toe_end;
    if (m.toe[side] >= 0)
    {
      ball = P (m.toe[side]);
      toe_end = m.toe_end[side] >= 0 && (P (m.toe_end[side]) - ball).norm () > 0.02 * s
                    ? P (m.toe_end[side])
                    : Eigen::Vector3d (ball + B (m.toe[side]).col (2) * 0.055 * s);
    }
    else
    {
      ball = an + fb * Eigen::Vector3d (0, -0.025, 0.13) * s;
      toe_end = ball + fb.col (2) * 0.055 * s;
    }
    const double foot_r = 0.04 * s * (0.5 + 0.5 * bp.girth), toe_r = 0.028 * s * (0.5 + 0.5 * bp.girth);
    body.tip_primitives[3 + side] = {static_cast<int> (body.primitives.size ()),
                                     static_cast<int> (body.primitives.size ()) + 1};
    body.tip_tolerance[3 + side] = foot_r + 0.03;
    material = SynthMaterial::Shoes;
    part = sided (side, SynthPart::LeftFoot, SynthPart::RightFoot);
    capsule (heel, ball, foot_r);
    capsule (ball, toe_end, toe_r);
    body.tip[3 + side] = toe_end + (toe_end - ball).normalized () * toe_r;
    body.base[3 + side] = an;
  }

  body.centre = 0.5 * (P (m.root) + P (m.neck));
  body.lowest = kInf;
  body.highest = -kInf;
  for (const auto &p : body.primitives)
  {
    if (p.shape == SynthPrimitive::Shape::Capsule)
    {
      body.lowest = std::min (body.lowest, std::min (p.a.y (), p.b.y ()) - p.radius);
      body.highest = std::max (body.highest, std::max (p.a.y (), p.b.y ()) + p.radius);
    }
    else
    {
      body.lowest = std::min (body.lowest, p.centre.y () - p.axes.row (1).norm ());
      body.highest = std::max (body.highest, p.centre.y () + p.axes.row (1).norm ());
    }
  }
  return body;
}

double
restStandingHeight (const MotionClip &clip, const BodyParams &params)
{
  const BodyModel body = buildBody (clip, -1, params);
  return body.highest - body.lowest;
}
}  // namespace agex
