#include <agex/simulation/synthetic_scene.h>

#include <agex/simulation/human_mesh.h>
#include <agex/simulation/make_human_targets.h>

#include <pcl/common/io.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <numeric>
#include <set>
#include <sstream>
#include <stdexcept>

namespace agex
{
namespace
{
constexpr double kInf = std::numeric_limits<double>::infinity ();
const float kNaN = std::numeric_limits<float>::quiet_NaN ();

std::uint64_t
splitMix64 (std::uint64_t x)
{
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

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

Eigen::Matrix3d
inverseOfOrthogonalColumns (const Eigen::Matrix3d &axes)
{
  Eigen::Matrix3d inv = axes.transpose ();
  for (int i = 0; i < 3; ++i)
  {
    const double n2 = axes.col (i).squaredNorm ();
    inv.row (i) /= n2 > 0 ? n2 : 1.0;
  }
  return inv;
}

/** Ray-sphere: nearest t > t_min, -1 if none. */
inline double
sphereHit (const Eigen::Vector3d &o, const Eigen::Vector3d &d, const Eigen::Vector3d &c, double r, double t_min)
{
  const Eigen::Vector3d oc = o - c;
  const double b = oc.dot (d);
  const double cc = oc.squaredNorm () - r * r;
  const double h = b * b - cc;
  if (h < 0)
    return -1.0;
  const double s = std::sqrt (h);
  if (-b - s > t_min)
    return -b - s;
  if (-b + s > t_min)
    return -b + s;
  return -1.0;
}
}  // namespace

// ---------------------------------------------------------------------------
// SynthRng

SynthRng
SynthRng::forItem (std::uint64_t seed, std::uint64_t index)
{
  return SynthRng (splitMix64 (splitMix64 (seed) ^ splitMix64 (index + 0x632BE59BD9B4E019ull)));
}

double
SynthRng::uniform ()
{
  return static_cast<double> (engine_ () >> 11) * (1.0 / 9007199254740992.0);
}

int
SynthRng::index (int n)
{
  if (n <= 1)
    return 0;
  return std::min (n - 1, static_cast<int> (uniform () * n));
}

double
SynthRng::normal ()
{
  if (have_spare_)
  {
    have_spare_ = false;
    return spare_;
  }
  const double u1 = 1.0 - uniform ();  // (0, 1]
  const double u2 = uniform ();
  const double r = std::sqrt (-2.0 * std::log (u1));
  spare_ = r * std::sin (2.0 * M_PI * u2);
  have_spare_ = true;
  return r * std::cos (2.0 * M_PI * u2);
}

// ---------------------------------------------------------------------------
// Sensors

const char *
synthSensorName (SynthSensor sensor)
{
  switch (sensor)
  {
    case SynthSensor::Sr4000: return "sr4000";
    case SynthSensor::Kinect: return "kinect";
    case SynthSensor::Bonn: return "bonn";
  }
  return "?";
}

bool
parseSynthSensor (const std::string &name, SynthSensor &sensor)
{
  if (name == "sr4000")
    sensor = SynthSensor::Sr4000;
  else if (name == "kinect")
    sensor = SynthSensor::Kinect;
  else if (name == "bonn")
    sensor = SynthSensor::Bonn;
  else
    return false;
  return true;
}

SensorModel
sensorModel (SynthSensor sensor)
{
  if (sensor == SynthSensor::Bonn)
  {
    // The portrait view of a kinect frame, with the intrinsics agex_convert bonn writes.
    SensorModel m = sensorModel (SynthSensor::Kinect);
    const FrameView view = bonnPortraitView ();
    m.sensor = sensor;
    m.width = view.outputWidth ();
    m.height = view.outputHeight ();
    m.intrinsics = view.intrinsics (m.intrinsics);
    return m;
  }
  SensorModel m;
  m.sensor = sensor;
  if (sensor == SynthSensor::Sr4000)
  {
    // 176x144 at fx = fy = 220 (43.6 x 36.2 degrees), rotated by 90 degrees.
    m.width = 144;
    m.height = 176;
    m.intrinsics.fx = m.intrinsics.fy = 220.0;
    m.intrinsics.cx = 71.5;
    m.intrinsics.cy = 87.5;
    m.supersample = 3;
    m.min_range = 0.1;
    m.max_range = 5.0;  // the non-ambiguity range at 30 MHz
  }
  else
  {
    m.width = 640;
    m.height = 480;
    m.intrinsics = CameraIntrinsics ();  // 525, 525, 319.5, 239.5
    m.supersample = 1;
    m.min_range = 0.5;
    m.max_range = 6.0;
  }
  return m;
}

SensorModel
renderSensorModel (SynthSensor sensor)
{
  return sensorModel (sensor == SynthSensor::Bonn ? SynthSensor::Kinect : sensor);
}

// ---------------------------------------------------------------------------
// Primitives

SynthPrimitive
SynthPrimitive::capsule (const Eigen::Vector3d &a, const Eigen::Vector3d &b, double radius, SynthObject object)
{
  SynthPrimitive p;
  p.shape = Shape::Capsule;
  p.object = object;
  p.a = a;
  p.b = b;
  p.radius = radius;
  return p;
}

SynthPrimitive
SynthPrimitive::ellipsoid (const Eigen::Vector3d &centre, const Eigen::Matrix3d &axes, SynthObject object)
{
  SynthPrimitive p;
  p.shape = Shape::Ellipsoid;
  p.object = object;
  p.centre = centre;
  p.axes = axes;
  p.inverse = inverseOfOrthogonalColumns (axes);
  return p;
}

SynthPrimitive
SynthPrimitive::box (const Eigen::Vector3d &centre, const Eigen::Matrix3d &axes, SynthObject object)
{
  SynthPrimitive p = ellipsoid (centre, axes, object);
  p.shape = Shape::Box;
  return p;
}

SynthPrimitive
SynthPrimitive::plane (const Eigen::Vector3d &normal, double offset, SynthObject object)
{
  SynthPrimitive p;
  p.shape = Shape::Plane;
  p.object = object;
  const double n = normal.norm ();
  p.normal = normal / n;
  p.offset = offset / n;
  return p;
}

SynthPrimitive
SynthPrimitive::triangleMesh (std::shared_ptr<const SynthMesh> mesh, SynthObject object)
{
  if (!mesh)
    throw std::invalid_argument ("SynthPrimitive::triangleMesh: no mesh");
  SynthPrimitive p;
  p.shape = Shape::Mesh;
  p.object = object;
  p.mesh = std::move (mesh);
  return p;
}

SynthPrimitive
SynthPrimitive::transformed (const Eigen::Isometry3d &t) const
{
  SynthPrimitive p = *this;
  p.a = t * a;
  p.b = t * b;
  p.centre = t * centre;
  p.axes = t.linear () * axes;
  p.inverse = inverseOfOrthogonalColumns (p.axes);
  p.normal = t.linear () * normal;
  p.offset = offset + p.normal.dot (t.translation ());
  return p;
}

bool
SynthPrimitive::boundingSphere (Eigen::Vector3d &c, double &r) const
{
  switch (shape)
  {
    case Shape::Capsule:
      c = 0.5 * (a + b);
      r = 0.5 * (b - a).norm () + radius;
      return true;
    case Shape::Ellipsoid:
      c = centre;
      r = std::max ({axes.col (0).norm (), axes.col (1).norm (), axes.col (2).norm ()});
      return true;
    case Shape::Box:
      c = centre;
      r = std::sqrt (axes.col (0).squaredNorm () + axes.col (1).squaredNorm () + axes.col (2).squaredNorm ());
      return true;
    case Shape::Mesh:
      c = centre + axes * mesh->sphereCentre ();
      r = mesh->sphereRadius ();
      return true;
    case Shape::Plane: return false;
  }
  return false;
}

double
SynthPrimitive::intersect (const Eigen::Vector3d &o, const Eigen::Vector3d &d, double t_min, Eigen::Vector3d *n,
                           int *triangle) const
{
  if (triangle)
    *triangle = -1;
  switch (shape)
  {
    case Shape::Capsule:
    {
      // Cylinder body (Inigo Quilez's formulation) and both end spheres.
      const Eigen::Vector3d ba = b - a, oa = o - a;
      const double baba = ba.squaredNorm (), bard = ba.dot (d), baoa = ba.dot (oa);
      const double rdoa = d.dot (oa), oaoa = oa.squaredNorm ();
      double best = -1.0;
      Eigen::Vector3d best_normal = Eigen::Vector3d::Zero ();
      const double qa = baba - bard * bard;
      if (qa > 1e-12 * baba)
      {
        const double qb = baba * rdoa - baoa * bard;
        const double qc = baba * oaoa - baoa * baoa - radius * radius * baba;
        const double h = qb * qb - qa * qc;
        if (h >= 0)
        {
          const double s = std::sqrt (h);
          for (const double t : {(-qb - s) / qa, (-qb + s) / qa})
          {
            const double y = baoa + t * bard;
            if (t > t_min && y > 0 && y < baba)
            {
              best = t;
              if (n)
                best_normal = (oa + t * d - ba * (y / baba)) / radius;
              break;
            }
          }
        }
      }
      for (const Eigen::Vector3d *c : {&a, &b})
      {
        const double t = sphereHit (o, d, *c, radius, t_min);
        if (t > t_min && (best < 0 || t < best))
        {
          best = t;
          if (n)
            best_normal = (o + t * d - *c) / radius;
        }
      }
      if (n && best > 0)
        *n = best_normal;
      return best;
    }
    case Shape::Ellipsoid:
    {
      const Eigen::Vector3d lo = inverse * (o - centre), ld = inverse * d;
      const double qa = ld.squaredNorm (), qb = lo.dot (ld), qc = lo.squaredNorm () - 1.0;
      const double h = qb * qb - qa * qc;
      if (h < 0)
        return -1.0;
      const double s = std::sqrt (h);
      double t = (-qb - s) / qa;
      if (t <= t_min)
        t = (-qb + s) / qa;
      if (t <= t_min)
        return -1.0;
      if (n)
        *n = (inverse.transpose () * (lo + t * ld)).normalized ();
      return t;
    }
    case Shape::Box:
    {
      const Eigen::Vector3d lo = inverse * (o - centre), ld = inverse * d;
      double t_near = -kInf, t_far = kInf;
      int axis_near = 0, axis_far = 0;
      for (int i = 0; i < 3; ++i)
      {
        if (std::abs (ld[i]) < 1e-15)
        {
          if (std::abs (lo[i]) > 1.0)
            return -1.0;
          continue;
        }
        double t1 = (-1.0 - lo[i]) / ld[i], t2 = (1.0 - lo[i]) / ld[i];
        if (t1 > t2)
          std::swap (t1, t2);
        if (t1 > t_near)
        {
          t_near = t1;
          axis_near = i;
        }
        if (t2 < t_far)
        {
          t_far = t2;
          axis_far = i;
        }
      }
      if (t_near > t_far)
        return -1.0;
      double t = t_near;
      int axis = axis_near;
      if (t <= t_min)
      {
        t = t_far;
        axis = axis_far;
      }
      if (t <= t_min)
        return -1.0;
      if (n)
      {
        const double side = (lo[axis] + t * ld[axis]) >= 0 ? 1.0 : -1.0;
        *n = side * axes.col (axis).normalized ();
      }
      return t;
    }
    case Shape::Plane:
    {
      const double denom = normal.dot (d);
      if (std::abs (denom) < 1e-12)
        return -1.0;
      const double t = (offset - normal.dot (o)) / denom;
      if (t <= t_min)
        return -1.0;
      if (n)
        *n = denom < 0 ? normal : Eigen::Vector3d (-normal);
      return t;
    }
    case Shape::Mesh:
    {
      // The placement is rigid, so t is the same in the mesh's own frame.
      const double t = mesh->intersect (axes.transpose () * (o - centre), axes.transpose () * d, t_min, n, triangle);
      if (t >= 0 && n)
        *n = axes * *n;
      return t;
    }
  }
  return -1.0;
}

SynthPart
SynthPrimitive::partAt (int triangle) const
{
  if (object != SynthObject::Person)
    return SynthPart::None;
  SynthPart p = part;
  if (triangle_parts && triangle >= 0 && static_cast<std::size_t> (triangle) < triangle_parts->size ())
    p = (*triangle_parts)[static_cast<std::size_t> (triangle)];
  return p == SynthPart::None ? SynthPart::Unknown : p;
}

double
SynthPrimitive::distance (const Eigen::Vector3d &p) const
{
  switch (shape)
  {
    case Shape::Capsule:
    {
      const Eigen::Vector3d ba = b - a;
      const double len2 = ba.squaredNorm ();
      const double t = len2 > 0 ? std::clamp ((p - a).dot (ba) / len2, 0.0, 1.0) : 0.0;
      return (p - (a + t * ba)).norm () - radius;
    }
    case Shape::Ellipsoid:
    {
      // p/r and p/r^2 in the ellipsoid's own frame (Quilez's bound, exact on the surface).
      const Eigen::Vector3d q = inverse * (p - centre);
      Eigen::Vector3d q2;
      for (int i = 0; i < 3; ++i)
        q2[i] = q[i] / axes.col (i).norm ();
      const double k0 = q.norm (), k1 = q2.norm ();
      return k1 > 0 ? k0 * (k0 - 1.0) / k1 : -axes.col (0).norm ();
    }
    case Shape::Box:
    {
      Eigen::Vector3d d;
      for (int i = 0; i < 3; ++i)
      {
        const double h = axes.col (i).norm ();
        d[i] = std::abs ((p - centre).dot (axes.col (i)) / h) - h;
      }
      const Eigen::Vector3d outside = d.cwiseMax (0.0);
      return outside.norm () + std::min (d.maxCoeff (), 0.0);
    }
    case Shape::Plane: return normal.dot (p) - offset;
    case Shape::Mesh: return mesh->distance (axes.transpose () * (p - centre));
  }
  return kInf;
}

SynthScene
SynthScene::transformed (const Eigen::Isometry3d &transform) const
{
  SynthScene s;
  s.primitives.reserve (primitives.size ());
  for (const auto &p : primitives)
    s.primitives.push_back (p.transformed (transform));
  return s;
}

double
SynthScene::distance (const Eigen::Vector3d &p, SynthObject object) const
{
  double best = kInf;
  for (const auto &prim : primitives)
    if (prim.object == object)
      best = std::min (best, prim.distance (p));
  return best;
}

// ---------------------------------------------------------------------------
// Bodies

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

std::string
BodyParams::describe () const
{
  return "height_scale=" + fixed (height_scale) + " girth=" + fixed (girth) + " head_scale=" + fixed (head_scale) +
         " arm_girth=" + fixed (arm_girth) + " leg_girth=" + fixed (leg_girth) + " torso_depth=" + fixed (torso_depth) +
         " reflectivity=" + fixed (reflectivity, 2);
}

namespace
{
/** First joint (not an End Site) with one of the names, -1 if none. */
int
findAny (const BvhMotion &motion, const std::vector<std::string> &names)
{
  for (const auto &name : names)
  {
    const int j = motion.findJoint (name);
    if (j >= 0 && !motion.joints ()[j].end_site)
      return j;
  }
  return -1;
}

std::vector<std::string>
sided (const std::vector<std::string> &patterns, const std::string &side)
{
  std::vector<std::string> names;
  for (std::string p : patterns)
  {
    const auto at = p.find ('*');
    if (at != std::string::npos)
      p.replace (at, 1, side);
    names.push_back (p);
  }
  return names;
}

std::string
joinNames (const std::vector<std::string> &names)
{
  std::string s;
  for (const auto &n : names)
    s += (s.empty () ? "" : ", ") + n;
  return s;
}

bool
isDescendant (const BvhMotion &motion, int joint, int ancestor)
{
  for (int j = joint; j >= 0; j = motion.joints ()[j].parent)
    if (j == ancestor)
      return true;
  return false;
}

int
endSiteOf (const BvhMotion &motion, int joint)
{
  for (std::size_t j = 0; j < motion.joints ().size (); ++j)
    if (motion.joints ()[j].parent == joint && motion.joints ()[j].end_site)
      return static_cast<int> (j);
  return -1;
}
}  // namespace

SkeletonMap
SkeletonMap::find (const BvhMotion &motion)
{
  SkeletonMap m;
  const std::string &path = motion.path ();
  auto require = [&] (const std::vector<std::string> &names, const std::string &what) {
    const int j = findAny (motion, names);
    if (j < 0)
      throw BvhError (path + ": no joint for the " + what + " (looked for " + joinNames (names) +
                      "); the synthetic body needs a CMU-style human skeleton");
    return j;
  };
  m.root = 0;
  m.head = require ({"Head"}, "head");
  m.neck = require ({"lowerneck", "Neck", "Neck1"}, "neck");
  m.spine_mid = require ({"Spine", "Chest", "Spine1"}, "middle of the spine");
  m.spine_base = findAny (motion, {"LowerBack", "Spine0"});
  if (m.spine_base < 0)
    m.spine_base = m.root;
  m.head_end = endSiteOf (motion, m.head);

  std::vector<Eigen::Isometry3d> rest;
  motion.pose (-1, 1.0, rest);
  auto P = [&] (int j) { return rest[j].translation (); };

  const char *side_names[2] = {"Left", "Right"};
  for (int s = 0; s < 2; ++s)
  {
    const std::string side = side_names[s];
    const std::string lower = s == 0 ? "left " : "right ";
    m.shoulder[s] = require (sided ({"*Arm", "*UpArm", "*UpperArm", "*Shoulder"}, side), lower + "upper arm");
    m.elbow[s] = require (sided ({"*ForeArm", "*Elbow", "*LowerArm"}, side), lower + "elbow");
    m.wrist[s] = require (sided ({"*Hand", "*Wrist"}, side), lower + "wrist");
    m.hip[s] = require (sided ({"*UpLeg", "*Hip", "*Thigh", "*UpperLeg"}, side), lower + "hip");
    m.knee[s] = require (sided ({"*Leg", "*Knee", "*Shin", "*LowerLeg"}, side), lower + "knee");
    m.ankle[s] = require (sided ({"*Foot", "*Ankle"}, side), lower + "ankle");
    m.toe[s] = findAny (motion, sided ({"*ToeBase", "*Toe", "*Toes"}, side));
    if (m.toe[s] >= 0 && !isDescendant (motion, m.toe[s], m.ankle[s]))
      m.toe[s] = -1;
    const int toe_end = m.toe[s] >= 0 ? endSiteOf (motion, m.toe[s]) : -1;
    m.toe_end[s] = toe_end >= 0 && (P (toe_end) - P (m.toe[s])).norm () > 1e-9 ? toe_end : -1;
    // The hand's end: the descendant of the wrist farthest along the forearm (fingers,
    // not the thumb), if it is away from the wrist at all.
    const Eigen::Vector3d forearm = (P (m.wrist[s]) - P (m.elbow[s])).normalized ();
    double best = 0.0;
    for (std::size_t j = 0; j < motion.joints ().size (); ++j)
      if (static_cast<int> (j) != m.wrist[s] && isDescendant (motion, static_cast<int> (j), m.wrist[s]))
      {
        const double along = (P (static_cast<int> (j)) - P (m.wrist[s])).dot (forearm);
        if (along > best)
        {
          best = along;
          m.hand_end[s] = static_cast<int> (j);
        }
      }
  }
  for (int s = 0; s < 2; ++s)
    if (m.shoulder[s] == m.shoulder[1 - s] || m.hip[s] == m.hip[1 - s])
      throw BvhError (path + ": left and right limbs are the same joints");

  // Rest-pose basis: the subject's left (from the hips), up (root to neck), forward.
  Eigen::Vector3d left = P (m.hip[0]) - P (m.hip[1]);
  Eigen::Vector3d up = P (m.neck) - P (m.root);
  if (left.norm () < 1e-9 || up.norm () < 1e-9)
    throw BvhError (path + ": degenerate rest pose (hips or spine of zero length)");
  left.normalize ();
  up = (up - up.dot (left) * left);
  if (up.norm () < 1e-9)
    throw BvhError (path + ": degenerate rest pose (spine along the hips)");
  up.normalize ();
  m.rest_basis << left, up, left.cross (up);
  return m;
}

MotionClip
MotionClip::load (const std::string &path, double scale)
{
  MotionClip clip;
  clip.motion = BvhMotion::read (path);
  if (clip.motion.frameCount () < 1)
    throw BvhError (path + ": the MOTION section has no frames");
  clip.map = SkeletonMap::find (clip.motion);
  clip.scale_auto = !(scale > 0);
  clip.scale = clip.scale_auto ? autoBvhScale (clip.motion) : scale;
  clip.sequence = std::filesystem::path (path).stem ().string ();
  if (clip.sequence.empty ())
    clip.sequence = "motion";
  return clip;
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

// ---------------------------------------------------------------------------
// Rendering

namespace
{
struct Hit
{
  double t = -1.0;  ///< along the unit ray, -1 = none
  int primitive = -1;
  int triangle = -1;  ///< of a mesh primitive
  double cos = 0.0;
};

/** Screen-space bins of a scene's bounded primitives (planes are tested everywhere). */
class Binner
{
public:
  static constexpr int kTile = 8;

  Binner (const SynthScene &scene, const SensorModel &sensor, double widen_right_px_m, double widen_left_px_m)
    : scene_ (scene), w_ (sensor.width), h_ (sensor.height)
  {
    tiles_x_ = (w_ + kTile - 1) / kTile;
    tiles_y_ = (h_ + kTile - 1) / kTile;
    bins_.resize (static_cast<std::size_t> (tiles_x_) * tiles_y_);
    const CameraIntrinsics &k = sensor.intrinsics;
    for (std::size_t i = 0; i < scene.primitives.size (); ++i)
    {
      const SynthPrimitive &p = scene.primitives[i];
      Eigen::Vector3d c;
      double r;
      if (!p.boundingSphere (c, r))
      {
        planes_.push_back (static_cast<int> (i));
        continue;
      }
      if (c.z () + r < 0.01)
        continue;  // behind the camera
      Box box;
      box.index = static_cast<int> (i);
      box.c = c;
      box.r2 = r * r;
      if (c.z () - r < 0.05)
      {
        box.u0 = 0;
        box.v0 = 0;
        box.u1 = w_ - 1;
        box.v1 = h_ - 1;
      }
      else
      {
        double u0 = kInf, u1 = -kInf, v0 = kInf, v1 = -kInf;
        for (const double z : {c.z () - r, c.z () + r})
          for (const double x : {c.x () - r, c.x () + r})
            for (const double y : {c.y () - r, c.y () + r})
            {
              const double u = k.fx * x / z + k.cx, v = k.fy * y / z + k.cy;
              u0 = std::min (u0, u);
              u1 = std::max (u1, u);
              v0 = std::min (v0, v);
              v1 = std::max (v1, v);
            }
        // Shadow rays from a projector beside the camera: widen along x by the disparity.
        const double zn = std::max (c.z () - r, 0.05);
        u0 -= widen_left_px_m / zn;
        u1 += widen_right_px_m / zn;
        if (u1 < -1 || v1 < -1 || u0 > w_ || v0 > h_)
          continue;
        box.u0 = std::max (0, static_cast<int> (std::floor (u0)) - 1);
        box.v0 = std::max (0, static_cast<int> (std::floor (v0)) - 1);
        box.u1 = std::min (w_ - 1, static_cast<int> (std::ceil (u1)) + 1);
        box.v1 = std::min (h_ - 1, static_cast<int> (std::ceil (v1)) + 1);
      }
      const int b = static_cast<int> (boxes_.size ());
      boxes_.push_back (box);
      for (int ty = box.v0 / kTile; ty <= box.v1 / kTile; ++ty)
        for (int tx = box.u0 / kTile; tx <= box.u1 / kTile; ++tx)
          bins_[static_cast<std::size_t> (ty) * tiles_x_ + tx].push_back (b);
    }
  }

  /** Nearest hit of the ray through pixel (u, v) (origin o, unit direction d). */
  Hit trace (int u, int v, const Eigen::Vector3d &o, const Eigen::Vector3d &d, bool planes) const
  {
    Hit best;
    Eigen::Vector3d n, best_n = Eigen::Vector3d::Zero ();
    int triangle = -1;
    if (planes)
      for (const int i : planes_)
      {
        const double t = scene_.primitives[i].intersect (o, d, 1e-6, &n);
        if (t > 0 && (best.t < 0 || t < best.t))
        {
          best.t = t;
          best.primitive = i;
          best.triangle = -1;
          best_n = n;
        }
      }
    for (const int b : bins_[static_cast<std::size_t> (v / kTile) * tiles_x_ + u / kTile])
    {
      const Box &box = boxes_[b];
      if (u < box.u0 || u > box.u1 || v < box.v0 || v > box.v1)
        continue;
      // Bounding sphere test first.
      const Eigen::Vector3d oc = box.c - o;
      const double along = oc.dot (d);
      if (oc.squaredNorm () - along * along > box.r2)
        continue;
      if (best.t > 0 && along - std::sqrt (box.r2) > best.t)
        continue;
      const double t = scene_.primitives[box.index].intersect (o, d, 1e-6, &n, &triangle);
      if (t > 0 && (best.t < 0 || t < best.t))
      {
        best.t = t;
        best.primitive = box.index;
        best.triangle = triangle;
        best_n = n;
      }
    }
    if (best.t > 0)
      best.cos = std::abs (best_n.dot (d));
    return best;
  }

  /** True if some bounded primitive may cover pixel (u, v). */
  bool anyAt (int u, int v) const
  {
    for (const int b : bins_[static_cast<std::size_t> (v / kTile) * tiles_x_ + u / kTile])
    {
      const Box &box = boxes_[b];
      if (u >= box.u0 && u <= box.u1 && v >= box.v0 && v <= box.v1)
        return true;
    }
    return false;
  }

  /** True if a bounded primitive blocks the segment o + t d, t in (0, length). */
  bool occluded (int u, int v, const Eigen::Vector3d &o, const Eigen::Vector3d &d, double length) const
  {
    for (const int b : bins_[static_cast<std::size_t> (v / kTile) * tiles_x_ + u / kTile])
    {
      const Box &box = boxes_[b];
      if (u < box.u0 || u > box.u1 || v < box.v0 || v > box.v1)
        continue;
      const Eigen::Vector3d oc = box.c - o;
      const double along = oc.dot (d);
      if (oc.squaredNorm () - along * along > box.r2)
        continue;
      const double t = scene_.primitives[box.index].intersect (o, d, 1e-6, nullptr);
      if (t > 0 && t < length)
        return true;
    }
    return false;
  }

private:
  struct Box
  {
    int index = 0, u0 = 0, v0 = 0, u1 = 0, v1 = 0;
    Eigen::Vector3d c;
    double r2 = 0.0;
  };
  const SynthScene &scene_;
  int w_, h_, tiles_x_ = 0, tiles_y_ = 0;
  std::vector<int> planes_;
  std::vector<Box> boxes_;
  std::vector<std::vector<int>> bins_;
};
}  // namespace

namespace
{
/** The unit ray through (sub)pixel (u, v) of a sensor. */
struct PixelRays
{
  const CameraIntrinsics &k;
  Eigen::Vector3d operator() (double u, double v) const
  {
    return Eigen::Vector3d ((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0).normalized ();
  }
};

/** Sizes the frame's cloud and ground truth to the sensor, everything invalid. */
void
resetFrame (const SynthScene &scene, const SensorModel &sensor, SynthFrame &frame)
{
  const int w = sensor.width, h = sensor.height;
  const std::size_t n = static_cast<std::size_t> (w) * h;
  frame.scene = scene;
  frame.cloud = pcl::PointCloud<pcl::PointXYZ> (static_cast<std::uint32_t> (w), static_cast<std::uint32_t> (h),
                                                pcl::PointXYZ (kNaN, kNaN, kNaN));
  frame.cloud.is_dense = false;
  frame.object.assign (n, SynthObject::None);
  frame.primitive.assign (n, -1);
  frame.ideal_z.assign (n, kNaN);
  frame.sample_min_z.assign (n, kNaN);
  frame.sample_max_z.assign (n, kNaN);
  frame.clean_z.assign (n, kNaN);
  frame.part_label.assign (n, 0);
  frame.person_label.assign (n, 0);
}

/** Pass 1: the nearest hit of the ray through every pixel centre (row-major). */
std::vector<Hit>
traceCentreRays (const Binner &binner, const SensorModel &sensor, const PixelRays &ray)
{
  const int w = sensor.width, h = sensor.height;
  const Eigen::Vector3d origin = Eigen::Vector3d::Zero ();
  std::vector<Hit> centre (static_cast<std::size_t> (w) * h);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
      centre[static_cast<std::size_t> (v) * w + u] = binner.trace (u, v, origin, ray (u, v), true);
  return centre;
}

/** True if the centre rays of pixel (u, v) and of its 8 neighbours (clamped at the
  * border) all see the same primitive. */
bool
neighboursSeeTheSamePrimitive (const std::vector<Hit> &centre, int u, int v, int w, int h)
{
  const std::size_t i = static_cast<std::size_t> (v) * w + u;
  for (int dv = -1; dv <= 1; ++dv)
    for (int du = -1; du <= 1; ++du)
    {
      const int uu = std::clamp (u + du, 0, w - 1), vv = std::clamp (v + dv, 0, h - 1);
      if (centre[static_cast<std::size_t> (vv) * w + uu].primitive != centre[i].primitive)
        return false;
    }
  return true;
}

/** The samples a pixel integrates: hits[0..count) along dirs[0..count), each standing
  * for `weight` of the ss x ss samples. */
struct PixelSamples
{
  std::vector<Hit> hits;
  std::vector<Eigen::Vector3d> dirs;
  std::size_t count = 1;
  double weight = 1.0;
  bool uniform = true;  ///< the centre sample stands for all of them

  explicit PixelSamples (int ss) : hits (static_cast<std::size_t> (ss) * ss), dirs (hits.size ()) {}
};

/** Pass 2 for one pixel: ss x ss samples where the centre rays of the pixel and its 8
  * neighbours do not all see the same primitive; elsewhere the centre sample stands for
  * all of them (a smooth surface averages to its centre value). */
void
samplePixel (const Binner &binner, const std::vector<Hit> &centre, const PixelRays &ray, int u, int v, int w, int h,
             int ss, PixelSamples &samples)
{
  const std::size_t i = static_cast<std::size_t> (v) * w + u;
  const Eigen::Vector3d origin = Eigen::Vector3d::Zero ();
  samples.uniform = ss <= 1 || neighboursSeeTheSamePrimitive (centre, u, v, w, h);
  samples.count = 1;
  if (samples.uniform)
  {
    samples.hits[0] = centre[i];
    samples.dirs[0] = ray (u, v);
  }
  else
  {
    samples.count = samples.hits.size ();
    for (int sy = 0; sy < ss; ++sy)
      for (int sx = 0; sx < ss; ++sx)
      {
        const std::size_t s = static_cast<std::size_t> (sy) * ss + sx;
        const double ou = (sx + 0.5) / ss - 0.5, ov = (sy + 0.5) / ss - 0.5;
        samples.dirs[s] = ray (u + ou, v + ov);
        samples.hits[s] = (ou == 0.0 && ov == 0.0) ? centre[i] : binner.trace (u, v, origin, samples.dirs[s], true);
      }
  }
  samples.weight = samples.uniform ? static_cast<double> (samples.hits.size ()) : 1.0;
}

/** What a pixel's samples add up to: hits per object class, the nearest depth per
  * class, the depth range, and the amplitude sums of the time-of-flight blend. */
struct PixelIntegral
{
  int counts[5] = {0, 0, 0, 0, 0};
  double nearest[5] = {kInf, kInf, kInf, kInf, kInf};
  double zmin = kInf, zmax = -kInf;
  double amp_sum = 0.0, amp_range = 0.0;
};

PixelIntegral
integratePixel (const SynthScene &scene, const PixelSamples &samples)
{
  PixelIntegral sum;
  for (std::size_t s = 0; s < samples.count; ++s)
  {
    const Hit &hit = samples.hits[s];
    if (hit.t < 0)
      continue;
    const double z = hit.t * samples.dirs[s].z ();
    sum.zmin = std::min (sum.zmin, z);
    sum.zmax = std::max (sum.zmax, z);
    const int obj = static_cast<int> (scene.primitives[hit.primitive].object);
    sum.counts[obj] += static_cast<int> (samples.weight);
    sum.nearest[obj] = std::min (sum.nearest[obj], z);
    const double amp = samples.weight * scene.primitives[hit.primitive].reflectivity * hit.cos / (hit.t * hit.t);
    sum.amp_sum += amp;
    sum.amp_range += amp * hit.t;
  }
  return sum;
}

/** The noise-free ground truth of pixel i: the object most samples hit (ties: the
  * nearer), the centre ray's depth and primitive, the samples' depth range. */
void
recordGroundTruth (const PixelIntegral &sum, const Hit &centre, const Eigen::Vector3d &centre_ray, std::size_t i,
                   SynthFrame &frame)
{
  int best = 0;
  for (int o = 1; o < 5; ++o)
    if (sum.counts[o] > sum.counts[best] ||
        (sum.counts[o] == sum.counts[best] && sum.counts[o] > 0 && sum.nearest[o] < sum.nearest[best]))
      best = o;
  frame.object[i] = sum.counts[best] > 0 ? static_cast<SynthObject> (best) : SynthObject::None;
  if (centre.t > 0)
  {
    frame.ideal_z[i] = static_cast<float> (centre.t * centre_ray.z ());
    frame.primitive[i] = centre.primitive;
  }
  if (sum.zmin <= sum.zmax)
  {
    frame.sample_min_z[i] = static_cast<float> (sum.zmin);
    frame.sample_max_z[i] = static_cast<float> (sum.zmax);
  }
}

/** Time of flight: the pixel integrates the returns of all its samples, each weighted
  * by its amplitude (reflectivity * cos / range^2): mixed pixels. False (no
  * measurement) below the confidence cut or outside the range. */
bool
measureTimeOfFlight (const PixelIntegral &sum, std::size_t samples, const SensorModel &sensor, float &range,
                     float &amplitude)
{
  const double a = sum.amp_sum / static_cast<double> (samples);
  if (sum.amp_sum <= 0 || a < sensor.tof_min_amplitude)
    return false;
  const double r = sum.amp_range / sum.amp_sum;
  if (r < sensor.min_range || r > sensor.max_range)
    return false;
  range = static_cast<float> (r);
  amplitude = static_cast<float> (a);
  return true;
}

/** Structured light: the centre ray's range, if the surface is not too oblique and its
  * depth in range. */
bool
measureStructuredLight (const Hit &centre, const Eigen::Vector3d &centre_ray, const SensorModel &sensor, float &range)
{
  if (centre.t < 0 || centre.cos < sensor.kinect_min_cos)
    return false;
  const double z = centre.t * centre_ray.z ();
  if (z < sensor.min_range || z > sensor.max_range)
    return false;
  range = static_cast<float> (centre.t);
  return true;
}

/** Labels pixel i with the part and person of the surface a hit shows (nothing for the
  * room or a miss). */
void
labelPixel (const SynthScene &scene, const Hit &hit, std::size_t i, SynthFrame &frame)
{
  if (hit.t < 0)
    return;
  const SynthPrimitive &p = scene.primitives[static_cast<std::size_t> (hit.primitive)];
  const SynthPart part = p.partAt (hit.triangle);
  if (part == SynthPart::None)
    return;
  frame.part_label[i] = static_cast<std::uint8_t> (part);
  frame.person_label[i] = std::max<std::uint8_t> (1, p.person);
}

/** Time of flight: the surface a blended range shows, the sample whose range is nearest
  * to it, if within 1 cm + 1% of the range; null for a flying pixel between surfaces. */
const Hit *
surfaceAtBlendedRange (const PixelSamples &samples, double range)
{
  const Hit *best = nullptr;
  double best_gap = kInf;
  for (std::size_t s = 0; s < samples.count; ++s)
  {
    const Hit &hit = samples.hits[s];
    if (hit.t < 0)
      continue;
    const double gap = std::abs (hit.t - range);
    if (gap < best_gap)
    {
      best_gap = gap;
      best = &hit;
    }
  }
  return best_gap <= 0.01 + 0.01 * range ? best : nullptr;
}

/** No label where the sensor gave no depth. */
void
clearLabelsWithoutDepth (SynthFrame &frame)
{
  for (std::size_t i = 0; i < frame.part_label.size (); ++i)
    if (!std::isfinite (frame.cloud.points[i].z))
      frame.part_label[i] = frame.person_label[i] = 0;
}

/** The point at range r along pixel (u, v)'s ray, as agex::depthImageToCloud places it. */
pcl::PointXYZ
pointOnPixelRay (const CameraIntrinsics &k, int u, int v, double z)
{
  return pcl::PointXYZ (static_cast<float> ((u - k.cx) * z / k.fx), static_cast<float> ((v - k.cy) * z / k.fy),
                        static_cast<float> (z));
}

/** sr4000: range noise along the ray, growing as the amplitude falls. */
void
addTimeOfFlightNoise (const std::vector<float> &range, const std::vector<float> &amplitudes, const SensorModel &sensor,
                      SynthRng &rng, SynthFrame &frame)
{
  const CameraIntrinsics &k = sensor.intrinsics;
  const int w = sensor.width, h = sensor.height;
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
    {
      const std::size_t i = static_cast<std::size_t> (v) * w + u;
      if (!std::isfinite (range[i]))
        continue;
      const double noise = rng.normal ();
      const double amplitude = amplitudes[i];
      const double sigma = std::min (sensor.tof_sigma0 + sensor.tof_sigma_k / amplitude, sensor.tof_sigma_max);
      const double r = range[i] + sigma * noise;
      const Eigen::Vector3d d = Eigen::Vector3d ((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0).normalized ();
      frame.cloud.points[i] = pointOnPixelRay (k, u, v, r * d.z ());
    }
}

/** Kinect projector shadows: the depth (z) of every measured pixel that the projector
  * (kinect_baseline to the camera's right, +x) lights, NaN for the others. */
std::vector<float>
projectorLitDepth (const SynthScene &scene, const SensorModel &sensor, const PixelRays &ray,
                   const std::vector<float> &range)
{
  const int w = sensor.width, h = sensor.height;
  const Eigen::Vector3d projector (sensor.kinect_baseline, 0.0, 0.0);
  // The segment from the projector (at +x) to a point seen at pixel u runs along the
  // pixel's row to the right, so an occluder at depth z_o shadows pixels up to
  // f b / z_o to its left: widen the occluders' bins to the left by that.
  const Binner shadow_bins (scene, sensor, 0.0, sensor.intrinsics.fx * sensor.kinect_baseline);
  std::vector<float> z (range.size (), kNaN);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
    {
      const std::size_t i = static_cast<std::size_t> (v) * w + u;
      if (!std::isfinite (range[i]))
        continue;
      const Eigen::Vector3d d = ray (u, v);
      const Eigen::Vector3d p = d * range[i];
      if (!shadow_bins.anyAt (u, v))
      {
        z[i] = static_cast<float> (p.z ());
        continue;
      }
      Eigen::Vector3d to = p - projector;
      const double length = to.norm ();
      to /= length;
      if (shadow_bins.occluded (u, v, projector, to, length - 0.005))
        continue;
      z[i] = static_cast<float> (p.z ());
    }
  return z;
}

/** Depth edges on the noise-free depth: a 4-neighbour more than 4 cm + 3% of the depth
  * away, or nothing (which counts as far). */
std::vector<std::uint8_t>
depthEdges (const std::vector<float> &ideal_z, int w, int h)
{
  std::vector<std::uint8_t> edge (ideal_z.size (), 0);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
    {
      const std::size_t i = static_cast<std::size_t> (v) * w + u;
      const float zi = ideal_z[i];
      if (!std::isfinite (zi))
        continue;
      const int du[4] = {1, -1, 0, 0}, dv[4] = {0, 0, 1, -1};
      for (int q = 0; q < 4; ++q)
      {
        const int uu = u + du[q], vv = v + dv[q];
        if (uu < 0 || vv < 0 || uu >= w || vv >= h)
          continue;
        const float zj = ideal_z[static_cast<std::size_t> (vv) * w + uu];
        if (!std::isfinite (zj) || std::abs (zj - zi) > 0.04 + 0.03 * zi)
        {
          edge[i] = 1;
          break;
        }
      }
    }
  return edge;
}

/** True if a pixel of the 3x3 window around (u, v) is a depth edge. */
bool
besideAnEdge (const std::vector<std::uint8_t> &edge, int u, int v, int w, int h)
{
  for (int dv = -1; dv <= 1; ++dv)
    for (int du = -1; du <= 1; ++du)
    {
      const int uu = u + du, vv = v + dv;
      if (uu >= 0 && vv >= 0 && uu < w && vv < h && edge[static_cast<std::size_t> (vv) * w + uu])
        return true;
    }
  return false;
}

/** Kinect: holes at depth edges, then disparity noise and quantisation in 1/8 pixel. */
void
dropEdgesAndQuantiseDisparity (const std::vector<float> &z, const std::vector<std::uint8_t> &edge,
                               const SensorModel &sensor, SynthRng &rng, SynthFrame &frame)
{
  const CameraIntrinsics &k = sensor.intrinsics;
  const int w = sensor.width, h = sensor.height;
  const double fb8 = 8.0 * sensor.kinect_f_ir * sensor.kinect_baseline;
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
    {
      const std::size_t i = static_cast<std::size_t> (v) * w + u;
      if (!std::isfinite (z[i]))
        continue;
      const bool near_edge = !edge[i] && besideAnEdge (edge, u, v, w, h);
      if ((edge[i] && rng.uniform () < sensor.kinect_edge_drop) ||
          (near_edge && rng.uniform () < sensor.kinect_edge_drop_near))
        continue;
      const double q = std::round (fb8 / z[i] + sensor.kinect_sigma_q * rng.normal ());
      if (q < 1.0)
        continue;
      const double zq = fb8 / q;
      if (zq < sensor.min_range || zq > sensor.max_range)
        continue;
      frame.cloud.points[i] = pointOnPixelRay (k, u, v, zq);
    }
}
}  // namespace

void
renderScene (const SynthScene &scene, const SensorModel &sensor, SynthRng &rng, SynthFrame &frame)
{
  if (sensor.sensor == SynthSensor::Bonn)
    throw std::invalid_argument ("renderScene: bonn frames are rendered with renderSensorModel (SynthSensor::Bonn), "
                                 "then made into the Bonn view");
  const int w = sensor.width, h = sensor.height;
  const std::size_t n = static_cast<std::size_t> (w) * h;
  const bool tof = sensor.sensor == SynthSensor::Sr4000;
  const PixelRays ray{sensor.intrinsics};
  resetFrame (scene, sensor, frame);

  const Binner binner (scene, sensor, 0.0, 0.0);
  const std::vector<Hit> centre = traceCentreRays (binner, sensor, ray);

  // Pass 2: each pixel's samples give its ground truth and its noise-free measurement.
  std::vector<float> range (n, kNaN);  // measured range along the pixel-centre ray, before noise
  std::vector<float> amplitudes (tof ? n : 0, 0.0f);
  PixelSamples samples (std::max (1, sensor.supersample));
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
    {
      const std::size_t i = static_cast<std::size_t> (v) * w + u;
      samplePixel (binner, centre, ray, u, v, w, h, std::max (1, sensor.supersample), samples);
      const PixelIntegral sum = integratePixel (scene, samples);
      recordGroundTruth (sum, centre[i], ray (u, v), i, frame);
      // The labels are those of the surface the measurement shows.
      if (tof)
      {
        if (measureTimeOfFlight (sum, samples.hits.size (), sensor, range[i], amplitudes[i]))
          if (const Hit *surface = surfaceAtBlendedRange (samples, range[i]))
            labelPixel (scene, *surface, i, frame);
      }
      else if (measureStructuredLight (centre[i], samples.dirs[0], sensor, range[i]))
        labelPixel (scene, centre[i], i, frame);
      if (std::isfinite (range[i]))
        frame.clean_z[i] = static_cast<float> (range[i] * ray (u, v).z ());
    }

  if (tof)
    addTimeOfFlightNoise (range, amplitudes, sensor, rng, frame);
  else
  {
    // Kinect: projector shadows, holes at depth edges, disparity quantisation.
    const std::vector<float> z = projectorLitDepth (scene, sensor, ray, range);
    dropEdgesAndQuantiseDisparity (z, depthEdges (frame.ideal_z, w, h), sensor, rng, frame);
  }
  clearLabelsWithoutDepth (frame);
}

int
labelWindow (const SensorModel &sensor)
{
  return sensor.sensor == SynthSensor::Kinect ? 2 : 1;
}

void
makeLabels (const BodyModel &body, const SensorModel &sensor, SynthFrame &frame)
{
  frame.labels.clear ();
  frame.label_checks.clear ();
  appendPersonLabels (body, sensor, 0, 1, frame);
}

void
appendPersonLabels (const BodyModel &body, const SensorModel &sensor, int first_primitive, int person,
                    SynthFrame &frame)
{
  const CameraIntrinsics &k = sensor.intrinsics;
  const int w = sensor.width, h = sensor.height, win = labelWindow (sensor);
  auto project = [&] (const Eigen::Vector3d &p) {
    const double z = std::max (p.z (), 1e-3);
    return Eigen::Vector2f (static_cast<float> (k.fx * p.x () / z + k.cx), static_cast<float> (k.fy * p.y () / z + k.cy));
  };
  auto visible = [&] (int index, const Eigen::Vector2f &px) {
    const Eigen::Vector3d &tip = body.tip[index];
    if (tip.z () < 0.05)
      return false;
    const long u = std::lround (px.x ()), v = std::lround (px.y ());
    if (u < 0 || v < 0 || u >= w || v >= h)
      return false;
    std::vector<int> own = body.tip_primitives[index];
    for (int &p : own)
      p += first_primitive;
    for (long vv = std::max (0L, v - win); vv <= std::min<long> (h - 1, v + win); ++vv)
      for (long uu = std::max (0L, u - win); uu <= std::min<long> (w - 1, u + win); ++uu)
      {
        const std::size_t i = static_cast<std::size_t> (vv) * w + uu;
        const float z = frame.cloud.points[i].z;
        if (std::isfinite (z) && std::abs (z - tip.z ()) < body.tip_tolerance[index] &&
            std::find (own.begin (), own.end (), frame.primitive[i]) != own.end ())
          return true;
      }
    return false;
  };
  auto label = [&] (BodyPart part, int index) {
    PartLabel l;
    l.part = part;
    l.tip = body.tip[index].cast<float> ();
    l.base = body.base[index].cast<float> ();
    l.tip_px = project (body.tip[index]);
    l.base_px = project (body.base[index]);
    l.visible = l.tip_px.allFinite () && l.base_px.allFinite () && visible (index, l.tip_px);
    if (!l.tip_px.allFinite () || !l.base_px.allFinite ())  // never: guards labels.csv against NaN pixels
      l.tip_px = l.base_px = Eigen::Vector2f (-1.0f, -1.0f);
    l.keyframe = true;
    l.person = person;
    SynthLabelCheck check{body.tip_primitives[index], body.tip_tolerance[index]};
    for (int &p : check.primitives)
      p += first_primitive;
    return std::make_pair (l, check);
  };
  auto push = [&] (const std::pair<PartLabel, SynthLabelCheck> &l) {
    frame.labels.push_back (l.first);
    frame.label_checks.push_back (l.second);
  };
  push (label (BodyPart::Head, 0));
  for (const BodyPart part : {BodyPart::Hand, BodyPart::Foot})
  {
    const int first = part == BodyPart::Hand ? 1 : 3;
    auto a = label (part, first), b = label (part, first + 1);
    if (b.first.tip_px.x () < a.first.tip_px.x ())
      std::swap (a, b);
    a.first.instance = 0;
    b.first.instance = 1;
    push (a);
    push (b);
  }
}

// ---------------------------------------------------------------------------
// The generator

namespace
{
/** A kinect frame made to look like the Bonn frames: depth in 8-bit steps of
  * kBonnDepthStep (0 and beyond 255 steps: no measurement), each point kept on its
  * pixel's ray, then the portrait view (nearest source pixel, as agex_convert bonn
  * does). The ground truth follows the view, so labels are made in it. */
void
toBonnView (const SensorModel &kinect, const SensorModel &bonn, SynthFrame &frame)
{
  const CameraIntrinsics &k = kinect.intrinsics;
  for (int v = 0; v < kinect.height; ++v)
    for (int u = 0; u < kinect.width; ++u)
    {
      pcl::PointXYZ &p = frame.cloud (u, v);
      if (!std::isfinite (p.z))
        continue;
      const long level = std::lround (p.z / kBonnDepthStep);
      if (level < 1 || level > 255)
      {
        p.x = p.y = p.z = kNaN;
        continue;
      }
      const double z = static_cast<double> (level) * kBonnDepthStep;
      p.x = static_cast<float> ((u - k.cx) * z / k.fx);
      p.y = static_cast<float> ((v - k.cy) * z / k.fy);
      p.z = static_cast<float> (z);
    }
  const FrameView view = bonnPortraitView ();
  pcl::PointCloud<pcl::PointXYZ> portrait;
  applyView (frame.cloud, view, portrait);
  frame.cloud = std::move (portrait);
  auto resample = [&] (auto &values) {
    auto source = values;
    values.resize (static_cast<std::size_t> (bonn.width) * bonn.height);
    for (int v = 0; v < bonn.height; ++v)
      for (int u = 0; u < bonn.width; ++u)
      {
        const cv::Point s = view.sourcePixel (u, v);
        values[static_cast<std::size_t> (v) * bonn.width + u] =
            source[static_cast<std::size_t> (s.y) * kinect.width + s.x];
      }
  };
  resample (frame.object);
  resample (frame.primitive);
  resample (frame.ideal_z);
  resample (frame.sample_min_z);
  resample (frame.sample_max_z);
  resample (frame.clean_z);
  resample (frame.part_label);
  resample (frame.person_label);
  clearLabelsWithoutDepth (frame);  // the 8-bit depth steps drop some
}
}  // namespace

namespace
{
/** Distances left at 0: 1.5-3.5 m for one person (aimed at), 0.8-6 m for several. */
SynthOptions
withDefaultDistances (SynthOptions options)
{
  const bool several = options.people > 1;
  if (options.min_distance == 0.0)
    options.min_distance = several ? 0.8 : 1.5;
  if (options.max_distance == 0.0)
    options.max_distance = several ? 6.0 : 3.5;
  return options;
}
}  // namespace

SynthGenerator::SynthGenerator (const SynthOptions &options_in)
  : options_ (withDefaultDistances (options_in)), sensor_ (sensorModel (options_in.sensor)),
    render_sensor_ (renderSensorModel (options_in.sensor))
{
  const SynthOptions &options = options_;
  if (options.motion_files.empty ())
    throw std::invalid_argument ("no motion files given");
  if (options.subjects < 1)
    throw std::invalid_argument ("the number of subjects must be at least 1");
  if (options.people < 1 || options.people > 4)
    throw std::invalid_argument ("the number of people per frame must be 1-4, got " + std::to_string (options.people));
  if (!(options.min_distance > 0.3) || options.max_distance < options.min_distance)
    throw std::invalid_argument ("camera distances must satisfy 0.3 < min <= max");
  if (options.max_height < options.min_height)
    throw std::invalid_argument ("camera heights must satisfy min <= max");
  if (options.colour && options.sensor == SynthSensor::Bonn)
    throw std::invalid_argument ("colour frames need sensor sr4000 or kinect (bonn frames are a grey depth view)");
  for (const auto &path : options.motion_files)
    clips_.push_back (MotionClip::load (path, options.bvh_scale));
  SynthRng rng = SynthRng::forItem (options.seed, ~0ull);
  for (int s = 0; s < options.subjects; ++s)
    subjects_.push_back (BodyParams::random (rng));
  if (options.body_shapes && options.body_mesh.empty ())
    throw std::invalid_argument ("body shapes need a MakeHuman body mesh (body_mesh)");
  if (!options.body_mesh.empty ())
    mesh_ = std::make_shared<const HumanMesh> (HumanMesh::load (options.body_mesh));
  if (options.body_shapes)
  {
    // Shapes from their own generator, so the subjects' BodyParams stay as without.
    SynthRng shape_rng = SynthRng::forItem (options.seed, ~1ull);
    const MakeHumanTargets targets = MakeHumanTargets::load (options.body_mesh, mesh_->baseVertexCount ());
    for (int s = 0; s < options.subjects; ++s)
    {
      shapes_.push_back (BodyShape::sample (shape_rng));
      shaped_.push_back (std::make_shared<const HumanMesh> (mesh_->shaped (targets, shapes_.back ())));
    }
  }
  // The floor of a clip for a subject: the lowest the body gets over the whole clip.
  floor_.resize (clips_.size ());
  for (std::size_t c = 0; c < clips_.size (); ++c)
    for (std::size_t s = 0; s < subjects_.size (); ++s)
    {
      const BodyParams &params = subjects_[s];
      const HumanMesh *mesh = this->mesh (static_cast<int> (s));
      double lowest = kInf;
      for (int f = 0; f < clips_[c].motion.frameCount (); ++f)
        lowest = std::min (lowest, mesh ? meshBodyLowest (clips_[c], f, params, *mesh)
                                        : buildBody (clips_[c], f, params).lowest);
      floor_[c].push_back (lowest);
    }
}

const HumanMesh *
SynthGenerator::mesh (int subject) const
{
  if (subject < 0 || subject >= static_cast<int> (subjects_.size ()))
    throw std::out_of_range ("subject " + std::to_string (subject) + " of " + std::to_string (subjects_.size ()));
  return shaped_.empty () ? mesh_.get () : shaped_[static_cast<std::size_t> (subject)].get ();
}

BodyModel
SynthGenerator::body (int clip, int clip_frame, int subject) const
{
  const MotionClip &c = clips_.at (static_cast<std::size_t> (clip));
  const BodyParams &params = subjects_.at (static_cast<std::size_t> (subject));
  const HumanMesh *mesh = this->mesh (subject);
  return mesh ? buildMeshBody (c, clip_frame, params, *mesh) : buildBody (c, clip_frame, params);
}

namespace
{
/** The camera at `camera` looking at `aim` (Y up: x right, y down, z forward), then
  * pitched by `pitch` about its x axis and rolled by `roll` about its view axis. */
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

/** Where the room is laid out: on the floor at floor_y, `ahead` the camera's horizontal
  * view direction, `lateral` to its left; walls and clutter are placed from `anchor`
  * (on the floor plan) and kept clear of the people's primitives and of the camera. */
struct RoomFrame
{
  Eigen::Vector3d anchor, ahead, lateral, camera;
  double floor_y = 0.0;
  const std::vector<SynthPrimitive> *people = nullptr;
  /** Clutter stands at anchor + ahead * [along_min, wall distance] + lateral * [-across, across]. */
  double along_min = -1.2, across = 1.8;
};

/** Moves a wall (normal . x = offset, normal towards the people) behind every person's
  * primitive. */
double
clearOfPeople (const RoomFrame &room, const Eigen::Vector3d &normal, double offset)
{
  for (const auto &p : *room.people)
  {
    Eigen::Vector3d c;
    double r;
    p.boundingSphere (c, r);
    offset = std::min (offset, normal.dot (c) - r - 0.05);
  }
  return offset;
}

/** Adds the floor, the back wall `wall_behind` beyond the anchor (turned by up to 30
  * degrees) and, in half the frames, a side wall; returns wall_behind. */
double
addFloorAndWalls (SynthRng &rng, const RoomFrame &room, SynthScene &world)
{
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY ();
  SynthPrimitive floor = SynthPrimitive::plane (up, room.floor_y, SynthObject::Floor);
  floor.reflectivity = static_cast<float> (rng.uniform (0.25, 0.6));
  world.primitives.push_back (floor);

  const double wall_behind = rng.uniform (0.7, 2.0);
  const double wall_yaw = rng.uniform (-30.0, 30.0) * M_PI / 180.0;
  {
    const Eigen::Vector3d normal = -(Eigen::AngleAxisd (wall_yaw, up) * room.ahead);
    Eigen::Vector3d at = room.anchor + room.ahead * wall_behind;
    const double offset = clearOfPeople (room, normal, normal.dot (at));
    SynthPrimitive wall = SynthPrimitive::plane (normal, offset, SynthObject::Wall);
    wall.reflectivity = static_cast<float> (rng.uniform (0.5, 0.9));
    world.primitives.push_back (wall);
  }
  const bool side_wall = rng.chance (0.5);
  const double side_sign = rng.chance (0.5) ? 1.0 : -1.0, side_distance = rng.uniform (1.0, 2.5);
  const float side_reflectivity = static_cast<float> (rng.uniform (0.5, 0.9));
  if (side_wall)
  {
    const Eigen::Vector3d normal = -side_sign * room.lateral;
    const double offset =
        clearOfPeople (room, normal, normal.dot (room.anchor + side_sign * room.lateral * side_distance));
    if (normal.dot (room.camera) - offset > 0.3)
    {
      SynthPrimitive wall = SynthPrimitive::plane (normal, offset, SynthObject::Wall);
      wall.reflectivity = side_reflectivity;
      world.primitives.push_back (wall);
    }
  }
  return wall_behind;
}

/** A spot on the floor for a piece of clutter of the given half diagonal: in the
  * clutter area, clear of the people (10 cm) and the camera (40 cm), in front of the
  * walls; false after 20 attempts. */
bool
placeClutter (SynthRng &rng, const RoomFrame &room, double wall_behind, const SynthScene &world, double half_diagonal,
              Eigen::Vector3d &at)
{
  for (int attempt = 0; attempt < 20; ++attempt)
  {
    // Drawn across first, then along: the order earlier builds evaluated them in.
    const double across = rng.uniform (-room.across, room.across);
    const double along = rng.uniform (room.along_min, wall_behind);
    at = room.anchor + room.ahead * along + room.lateral * across;
    at.y () = room.floor_y;
    bool ok = true;
    for (const auto &p : *room.people)
    {
      Eigen::Vector3d c;
      double r;
      p.boundingSphere (c, r);
      const Eigen::Vector2d dxz (c.x () - at.x (), c.z () - at.z ());
      ok = ok && dxz.norm () > half_diagonal + r + 0.1;
    }
    const Eigen::Vector2d to_camera (room.camera.x () - at.x (), room.camera.z () - at.z ());
    ok = ok && to_camera.norm () > half_diagonal + 0.4;
    for (const auto &p : world.primitives)  // in front of the walls
      if (p.object == SynthObject::Wall)
        ok = ok && p.normal.dot (at) - p.offset > half_diagonal + 0.02;
    if (ok)
      return true;
  }
  return false;
}

/** A clutter box turned by `yaw` about the vertical. */
void
addClutterBox (SynthScene &world, const Eigen::Vector3d &centre, const Eigen::Vector3d &half, double yaw, float refl)
{
  const Eigen::Matrix3d r = Eigen::AngleAxisd (yaw, Eigen::Vector3d::UnitY ()).toRotationMatrix ();
  SynthPrimitive b = SynthPrimitive::box (centre, r * half.asDiagonal (), SynthObject::Clutter);
  b.reflectivity = refl;
  world.primitives.push_back (b);
}

/** A desk: a top at 0.70-0.76 m on four legs, roughly facing the camera. */
void
addDesk (SynthRng &rng, const RoomFrame &room, double wall_behind, SynthScene &world)
{
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY ();
  const double half_z = rng.uniform (0.3, 0.4);  // last first: the order earlier builds used
  const double half_x = rng.uniform (0.5, 0.8);
  const Eigen::Vector3d half (half_x, 0.015, half_z);
  const double top = rng.uniform (0.70, 0.76);
  const double yaw = std::atan2 (room.ahead.x (), room.ahead.z ()) + rng.uniform (-0.3, 0.3);
  const float refl = static_cast<float> (rng.uniform (0.3, 0.9));
  Eigen::Vector3d at;
  if (!placeClutter (rng, room, wall_behind, world, std::hypot (half.x (), half.z ()), at))
    return;
  addClutterBox (world, at + up * (top - half.y ()), half, yaw, refl);
  const Eigen::Matrix3d r = Eigen::AngleAxisd (yaw, up).toRotationMatrix ();
  for (const double sx : {-1.0, 1.0})
    for (const double sz : {-1.0, 1.0})
    {
      const Eigen::Vector3d leg = at + r * Eigen::Vector3d (sx * (half.x () - 0.04), 0, sz * (half.z () - 0.04));
      addClutterBox (world, leg + up * (0.5 * (top - 2 * half.y ())),
                     Eigen::Vector3d (0.02, 0.5 * (top - 2 * half.y ()), 0.02), yaw, refl);
    }
}

/** A box 0.2-0.7 m wide and 0.16-1 m tall standing on the floor. */
void
addBox (SynthRng &rng, const RoomFrame &room, double wall_behind, SynthScene &world)
{
  const double hz = rng.uniform (0.1, 0.35), hy = rng.uniform (0.08, 0.5), hx = rng.uniform (0.1, 0.35);  // last first
  const Eigen::Vector3d half (hx, hy, hz);
  const double yaw = rng.uniform (0.0, M_PI);
  const float refl = static_cast<float> (rng.uniform (0.3, 0.9));
  Eigen::Vector3d at;
  if (placeClutter (rng, room, wall_behind, world, std::hypot (half.x (), half.z ()), at))
    addClutterBox (world, at + Eigen::Vector3d::UnitY () * half.y (), half, yaw, refl);
}

/** A chair: a seat 0.4-0.5 m wide at 0.42-0.48 m on four legs, a backrest 0.35-0.5 m
  * tall, turned at random. */
void
addChair (SynthRng &rng, const RoomFrame &room, double wall_behind, SynthScene &world)
{
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY ();
  const double half_w = rng.uniform (0.2, 0.25);
  const double seat = rng.uniform (0.42, 0.48);
  const double back = rng.uniform (0.35, 0.5);
  const double yaw = rng.uniform (0.0, 2.0 * M_PI);
  const float refl = static_cast<float> (rng.uniform (0.3, 0.9));
  Eigen::Vector3d at;
  if (!placeClutter (rng, room, wall_behind, world, std::sqrt (2.0) * half_w, at))
    return;
  const Eigen::Matrix3d r = Eigen::AngleAxisd (yaw, up).toRotationMatrix ();
  const double t = 0.015;  // half the thickness of the seat and the backrest
  addClutterBox (world, at + up * (seat - t), Eigen::Vector3d (half_w, t, half_w), yaw, refl);
  for (const double sx : {-1.0, 1.0})
    for (const double sz : {-1.0, 1.0})
    {
      const Eigen::Vector3d leg = at + r * Eigen::Vector3d (sx * (half_w - 0.02), 0, sz * (half_w - 0.02));
      addClutterBox (world, leg + up * (0.5 * (seat - 2 * t)), Eigen::Vector3d (0.015, 0.5 * (seat - 2 * t), 0.015), yaw,
                     refl);
    }
  addClutterBox (world, at + r * Eigen::Vector3d (0, 0, -(half_w - t)) + up * (seat + 0.5 * back),
                 Eigen::Vector3d (half_w, 0.5 * back, t), yaw, refl);
}

/** A shelf facing the camera near the back wall (within 0.6 m of where the wall was
  * drawn): 0.6-1.2 m wide, 0.3-0.4 m deep, 1.2-2 m tall; two sides, a back, a bottom, a
  * top and 1-3 boards between. */
void
addShelf (SynthRng &rng, const RoomFrame &room, double wall_behind, SynthScene &world)
{
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY ();
  const double half_w = rng.uniform (0.3, 0.6);
  const double half_d = rng.uniform (0.15, 0.2);
  const double height = rng.uniform (1.2, 2.0);
  const int boards = 1 + rng.index (3);
  const double yaw = std::atan2 (room.ahead.x (), room.ahead.z ()) + rng.uniform (-0.3, 0.3);
  const float refl = static_cast<float> (rng.uniform (0.3, 0.9));
  Eigen::Vector3d at;
  RoomFrame by_the_wall = room;
  by_the_wall.along_min = wall_behind - 0.6;
  if (!placeClutter (rng, by_the_wall, wall_behind, world, std::hypot (half_w, half_d), at))
    return;
  const Eigen::Matrix3d r = Eigen::AngleAxisd (yaw, up).toRotationMatrix ();  // local +z: away from the camera
  const double t = 0.01;
  for (const double sx : {-1.0, 1.0})
    addClutterBox (world, at + r * Eigen::Vector3d (sx * (half_w - t), 0, 0) + up * (0.5 * height),
                   Eigen::Vector3d (t, 0.5 * height, half_d), yaw, refl);
  addClutterBox (world, at + r * Eigen::Vector3d (0, 0, half_d - t) + up * (0.5 * height),
                 Eigen::Vector3d (half_w - 2 * t, 0.5 * height, t), yaw, refl);
  for (int b = 0; b <= boards + 1; ++b)
    addClutterBox (world, at + up * (t + b * (height - 2 * t) / (boards + 1)),
                   Eigen::Vector3d (half_w - 2 * t, t, half_d - 2 * t), yaw, refl);
}

/** The clutter of a scene with several people: a desk (30%), 0-2 chairs, a shelf (30%)
  * and 0-2 boxes. */
void
addGroupClutter (SynthRng &rng, const RoomFrame &room, double wall_behind, SynthScene &world)
{
  const bool desk = rng.chance (0.3);
  const int chairs = rng.index (3);
  const bool shelf = rng.chance (0.3);
  const int boxes = rng.index (3);
  if (desk)
    addDesk (rng, room, wall_behind, world);
  for (int c = 0; c < chairs; ++c)
    addChair (rng, room, wall_behind, world);
  if (shelf)
    addShelf (rng, room, wall_behind, world);
  for (int b = 0; b < boxes; ++b)
    addBox (rng, room, wall_behind, world);
}

/** How far a body reaches horizontally from its centre (the middle of its torso). */
double
horizontalReach (const BodyModel &body)
{
  auto off = [&] (const Eigen::Vector3d &p) { return std::hypot (p.x () - body.centre.x (), p.z () - body.centre.z ()); };
  double reach = 0.0;
  for (const auto &p : body.primitives)
  {
    if (p.shape == SynthPrimitive::Shape::Capsule)
      reach = std::max (reach, std::max (off (p.a), off (p.b)) + p.radius);
    else if (p.shape == SynthPrimitive::Shape::Mesh)
      for (const auto &v : p.mesh->vertices ())
        reach = std::max (reach, off (p.centre + p.axes * v));
    else
    {
      Eigen::Vector3d c;
      double r;
      if (p.boundingSphere (c, r))
        reach = std::max (reach, off (c) + r);
    }
  }
  return reach;
}

/** Where a placement stands on the floor plan: the camera at the origin looking along +z,
  * its right along -x. */
Eigen::Vector3d
placementSpot (const SynthPersonPlacement &p)
{
  return Eigen::Vector3d (-p.distance * std::sin (p.bearing), 0.0, p.distance * std::cos (p.bearing));
}

/** Where to put a person whose random spots were all taken: the free spot of a grid over
  * the ranges (25 cm by 1/14 of the bearings) nearest to the last spot drawn (p, which
  * it replaces); false if every grid spot is taken. */
bool
nearestFreeGridSpot (double min_distance, double max_distance, double max_bearing,
                     const std::function<bool (const SynthPersonPlacement &)> &free, SynthPersonPlacement &p)
{
  const SynthPersonPlacement last = p;
  double best = kInf;
  bool found = false;
  for (double d = min_distance; d <= max_distance + 1e-9; d += 0.25)
    for (int b = 0; b <= 14; ++b)
    {
      SynthPersonPlacement q = last;
      q.distance = d;
      q.bearing = max_bearing * (b / 7.0 - 1.0);
      const double gap = (placementSpot (q) - placementSpot (last)).norm ();
      if (gap < best && free (q))
      {
        best = gap;
        p = q;
        found = true;
      }
    }
  return found;
}

/** The stems of the people's motion files, sorted, without repeats, joined by '+'. */
std::string
groupSequence (const std::vector<MotionClip> &clips, const std::vector<SynthPersonPlacement> &people)
{
  std::set<std::string> stems;
  for (const auto &p : people)
    stems.insert (clips[static_cast<std::size_t> (p.clip)].sequence);
  std::string sequence;
  for (const auto &stem : stems)
    sequence += (sequence.empty () ? "" : "+") + stem;
  return sequence;
}

/** The room of a frame: floor, walls, then a desk (a quarter of the frames) or 0-3 boxes. */
void
addRoom (SynthRng &rng, const RoomFrame &room, SynthScene &world)
{
  const double wall_behind = addFloorAndWalls (rng, room, world);
  const bool desk = rng.chance (0.25);
  const int boxes = desk ? 0 : rng.index (4);
  if (desk)
    addDesk (rng, room, wall_behind, world);
  for (int b = 0; b < boxes; ++b)
    addBox (rng, room, wall_behind, world);
}
}  // namespace

SynthFrame
SynthGenerator::render (std::uint64_t index) const
{
  if (options_.people == 1)
    return renderOne (index);
  std::vector<BodyModel> bodies;
  const std::vector<SynthPersonPlacement> people = drawPeople (index, bodies);
  SynthRng rng = SynthRng::forItem (options_.seed, index);
  return renderGroup (rng, index, people, &bodies);
}

SynthFrame
SynthGenerator::renderPeople (std::uint64_t index, const std::vector<SynthPersonPlacement> &people) const
{
  if (people.empty () || people.size () > 255)
    throw std::invalid_argument ("renderPeople: 1-255 people");
  for (const auto &p : people)
    if (p.clip < 0 || p.clip >= static_cast<int> (clips_.size ()) || p.subject < 0 ||
        p.subject >= static_cast<int> (subjects_.size ()) || p.clip_frame < 0 ||
        p.clip_frame >= clips_[static_cast<std::size_t> (p.clip)].motion.frameCount () || !std::isfinite (p.distance) ||
        !std::isfinite (p.bearing) || !std::isfinite (p.facing))
      throw std::invalid_argument ("renderPeople: a placement's clip, clip frame or subject is out of range, or a "
                                   "distance or angle is not finite");
  SynthRng rng = SynthRng::forItem (options_.seed, index);
  return renderGroup (rng, index, people, nullptr);
}

std::vector<SynthPersonPlacement>
SynthGenerator::drawPeople (std::uint64_t index) const
{
  std::vector<BodyModel> bodies;
  return drawPeople (index, bodies);
}

double
SynthGenerator::horizontalFieldOfView () const
{
  return 2.0 * std::atan (0.5 * sensor_.width / sensor_.intrinsics.fx);
}

std::vector<SynthPersonPlacement>
SynthGenerator::drawPeople (std::uint64_t index, std::vector<BodyModel> &bodies) const
{
  // A stream of its own, so that renderPeople (i, drawPeople (i)) is render (i).
  SynthRng rng = SynthRng::forItem (options_.seed ^ 0x9E0913E5A11CE5EDull, index);
  const double half_fov = 0.5 * horizontalFieldOfView ();
  std::vector<SynthPersonPlacement> people;
  std::vector<double> reach;
  bodies.clear ();
  auto clear = [&] (const SynthPersonPlacement &p, double r) {
    for (std::size_t j = 0; j < people.size (); ++j)
      if ((placementSpot (p) - placementSpot (people[j])).norm () < r + reach[j] + 0.1)
        return false;
    return true;
  };
  for (int k = 0; k < options_.people; ++k)
  {
    SynthPersonPlacement p;
    p.clip = rng.index (static_cast<int> (clips_.size ()));
    p.clip_frame = rng.index (clips_[static_cast<std::size_t> (p.clip)].motion.frameCount ());
    p.subject = rng.index (static_cast<int> (subjects_.size ()));
    p.facing = rng.uniform (0.0, 2.0 * M_PI);
    BodyModel body = this->body (p.clip, p.clip_frame, p.subject);
    const double r = horizontalReach (body);
    // 40% of the people after the first stand in line with an earlier one (within 0.5 m
    // of its line of sight), so that one hides part of the other.
    const bool in_line = k > 0 && rng.chance (0.4);
    const int other = k > 0 ? rng.index (k) : 0;
    bool placed = false;
    for (int attempt = 0; attempt < 50 && !placed; ++attempt)
    {
      p.distance = rng.uniform (options_.min_distance, options_.max_distance);
      if (in_line)
      {
        const double lateral = rng.uniform (-0.5, 0.5);
        p.bearing = people[static_cast<std::size_t> (other)].bearing + lateral / p.distance;
      }
      else
        p.bearing = rng.uniform (-0.85 * half_fov, 0.85 * half_fov);
      placed = clear (p, r);
    }
    if (!placed)  // crowded
      placed = nearestFreeGridSpot (options_.min_distance, options_.max_distance, 0.85 * half_fov,
                                    [&] (const SynthPersonPlacement &q) { return clear (q, r); }, p);
    while (!placed)  // very rare: no room within the ranges; step back along the bearing
    {
      p.distance += 0.25;
      placed = clear (p, r);
    }
    people.push_back (p);
    reach.push_back (r);
    bodies.push_back (std::move (body));
  }
  // Person 1 is the nearest.
  std::vector<std::size_t> order (people.size ());
  std::iota (order.begin (), order.end (), 0);
  std::stable_sort (order.begin (), order.end (),
                    [&] (std::size_t a, std::size_t b) { return people[a].distance < people[b].distance; });
  std::vector<SynthPersonPlacement> sorted;
  std::vector<BodyModel> sorted_bodies;
  for (const std::size_t i : order)
  {
    sorted.push_back (people[i]);
    sorted_bodies.push_back (std::move (bodies[i]));
  }
  bodies = std::move (sorted_bodies);
  return sorted;
}

SynthFrame
SynthGenerator::renderGroup (SynthRng &rng, std::uint64_t index, const std::vector<SynthPersonPlacement> &people,
                             const std::vector<BodyModel> *bodies) const
{
  SynthFrame frame;
  frame.people = people;
  frame.clip = people.front ().clip;
  frame.clip_frame = people.front ().clip_frame;
  frame.subject = people.front ().subject;
  frame.sequence = groupSequence (clips_, people);
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY ();

  // The people on the floor plan (floor at y = 0): each body turned by its facing about
  // the vertical through its torso, which stands at its spot.
  std::vector<BodyModel> placed;
  std::vector<SynthPrimitive> people_primitives;
  std::vector<int> first_primitive;
  double mid_height = 0.0, mean_distance = 0.0, farthest = 0.0;
  for (std::size_t k = 0; k < people.size (); ++k)
  {
    const SynthPersonPlacement &p = people[k];
    const BodyModel body = bodies ? (*bodies)[k] : this->body (p.clip, p.clip_frame, p.subject);
    const double floor_y = floor_[static_cast<std::size_t> (p.clip)][static_cast<std::size_t> (p.subject)];
    const Eigen::Isometry3d to_plan = Eigen::Translation3d (placementSpot (p)) * Eigen::AngleAxisd (p.facing, up) *
                                      Eigen::Translation3d (-body.centre.x (), -floor_y, -body.centre.z ());
    placed.push_back (body.transformed (to_plan));
    first_primitive.push_back (static_cast<int> (people_primitives.size ()));
    for (SynthPrimitive prim : placed.back ().primitives)
    {
      prim.person = static_cast<std::uint8_t> (k + 1);
      people_primitives.push_back (std::move (prim));
    }
    mid_height += 0.5 * (body.lowest + body.highest) - floor_y;
    mean_distance += p.distance;
    farthest = std::max (farthest, placementSpot (p).z ());
  }
  mid_height /= static_cast<double> (people.size ());
  mean_distance /= static_cast<double> (people.size ());

  // The camera at the floor plan's origin, aimed along +z at the people's mean distance
  // and middle height, with a jitter (pan sigma ~3 degrees, 10 cm up or down), roll and pitch.
  const double height = rng.uniform (options_.min_height, options_.max_height);
  const Eigen::Vector3d camera (0.0, height, 0.0);
  Eigen::Vector3d aim (0.0, mid_height, mean_distance);
  aim.x () += rng.normal (0.0, 0.05 * mean_distance);
  aim.y () += rng.normal (0.0, 0.1);
  const double roll = rng.normal (0.0, 3.0) * M_PI / 180.0, pitch = rng.normal (0.0, 2.0) * M_PI / 180.0;
  frame.world_to_camera = worldToCamera (camera, aim, roll, pitch);

  // The room: walls behind the farthest person, clutter from 0.8 m in front of the
  // camera to the back wall, across the field of view.
  SynthScene world;
  world.primitives = people_primitives;
  RoomFrame room;
  room.ahead = aim - camera;
  room.ahead.y () = 0.0;
  room.ahead.normalize ();
  room.lateral = up.cross (room.ahead);
  room.camera = camera;
  room.floor_y = 0.0;
  room.anchor = room.ahead * farthest;
  room.people = &people_primitives;
  room.along_min = -(farthest - 0.8);
  room.across = std::max (1.8, (farthest + 1.0) * std::tan (0.5 * horizontalFieldOfView ()) + 0.5);
  const double wall_behind = addFloorAndWalls (rng, room, world);
  if (options_.clutter)
    addGroupClutter (rng, room, wall_behind, world);

  const SynthScene scene = world.transformed (frame.world_to_camera);
  renderScene (scene, render_sensor_, rng, frame);
  if (options_.colour)
  {
    SynthRng colour_rng = SynthRng::forItem (options_.seed ^ 0xC0105EEDC0105EEDull, index);
    shadeColour (render_sensor_, colour_rng, frame);
  }
  if (options_.sensor == SynthSensor::Bonn)
    toBonnView (render_sensor_, sensor_, frame);
  frame.labels.clear ();
  frame.label_checks.clear ();
  for (std::size_t k = 0; k < placed.size (); ++k)
    appendPersonLabels (placed[k].transformed (frame.world_to_camera), sensor_, first_primitive[k],
                        static_cast<int> (k + 1), frame);
  return frame;
}

SynthFrame
SynthGenerator::renderOne (std::uint64_t index) const
{
  SynthRng rng = SynthRng::forItem (options_.seed, index);
  SynthFrame frame;
  frame.clip = rng.index (static_cast<int> (clips_.size ()));
  const MotionClip &clip = clips_[frame.clip];
  frame.clip_frame = rng.index (clip.motion.frameCount ());
  frame.subject = rng.index (static_cast<int> (subjects_.size ()));
  frame.sequence = clip.sequence;
  const BodyModel body = this->body (frame.clip, frame.clip_frame, frame.subject);
  const double floor_y = floor_[frame.clip][frame.subject];

  // Camera: around the person at a random azimuth, distance and height, aimed at the
  // torso with a jitter (sometimes a large one, so the person leaves the frame).
  const double distance = rng.uniform (options_.min_distance, options_.max_distance);
  const double azimuth = rng.uniform (0.0, 2.0 * M_PI);
  const double height = rng.uniform (options_.min_height, options_.max_height);
  const Eigen::Vector3d camera (body.centre.x () + distance * std::cos (azimuth), floor_y + height,
                                body.centre.z () + distance * std::sin (azimuth));
  const double jitter = rng.chance (0.12) ? 0.35 : 0.1;
  Eigen::Vector3d aim (body.centre.x (), 0.5 * (body.lowest + body.highest), body.centre.z ());
  aim.x () += rng.normal (0.0, jitter);
  aim.y () += rng.normal (0.0, jitter);
  aim.z () += rng.normal (0.0, jitter);
  const double roll = rng.normal (0.0, 3.0) * M_PI / 180.0, pitch = rng.normal (0.0, 2.0) * M_PI / 180.0;
  frame.world_to_camera = worldToCamera (camera, aim, roll, pitch);

  // The room: floor, back wall behind the person, maybe a side wall, clutter.
  SynthScene world;
  world.primitives = body.primitives;
  RoomFrame room;
  room.anchor = body.centre;
  room.ahead = aim - camera;
  room.ahead.y () = 0.0;
  room.ahead.normalize ();
  room.lateral = Eigen::Vector3d::UnitY ().cross (room.ahead);  // to the camera's left
  room.camera = camera;
  room.floor_y = floor_y;
  room.people = &body.primitives;
  if (options_.clutter)
    addRoom (rng, room, world);
  else
    addFloorAndWalls (rng, room, world);

  const SynthScene scene = world.transformed (frame.world_to_camera);
  renderScene (scene, render_sensor_, rng, frame);
  if (options_.colour)
  {
    // A stream of its own, so colour frames have the same depth as depth-only ones.
    SynthRng colour_rng = SynthRng::forItem (options_.seed ^ 0xC0105EEDC0105EEDull, index);
    shadeColour (render_sensor_, colour_rng, frame);
  }
  if (options_.sensor == SynthSensor::Bonn)
    toBonnView (render_sensor_, sensor_, frame);
  makeLabels (body.transformed (frame.world_to_camera), sensor_, frame);
  return frame;
}

DatasetInfo
SynthGenerator::datasetInfo () const
{
  DatasetInfo info;
  info.name = std::string ("synthetic-") + synthSensorName (options_.sensor) + "-seed" + std::to_string (options_.seed);
  info.sensor = synthSensorName (options_.sensor);
  info.width = sensor_.width;
  info.height = sensor_.height;
  info.intrinsics = sensor_.intrinsics;
  info.depth_scale = 1.0;
  info.units = "m";
  info.part_labels = synthPartNames ();
  info.person_labels = true;
  std::ostringstream p;
  p << "agex_synth: synthetic " << info.sensor << " frames (" << sensor_.width << "x" << sensor_.height
    << ") of " << (mesh_ ? "MakeHuman mesh bodies (" + options_.body_mesh + ")" : std::string ("capsule/ellipsoid bodies"))
    << " posed by motion capture; motion:";
  for (const auto &clip : clips_)
    p << " " << clip.motion.path () << " (" << clip.motion.frameCount () << " frames, " << clip.scale << " m/unit"
      << (clip.scale_auto ? " auto" : "") << ")";
  p << "; seed " << options_.seed << "; camera " << options_.min_distance << "-" << options_.max_distance
    << " m from the body, " << options_.min_height << "-" << options_.max_height << " m high";
  if (options_.people > 1)
    p << "; " << options_.people << " people per frame (doc/synthetic.md, \"Several people\")";
  p << "; subjects:";
  for (std::size_t s = 0; s < subjects_.size (); ++s)
    p << " #" << s << " " << subjects_[s].describe ()
      << (s < shapes_.size () ? " shape " + shapes_[s].describe () + " (" + fixed (shaped_[s]->height ()) + " m)" : "")
      << (s + 1 < subjects_.size () ? ";" : "");
  p << "; each frame draws (clip, clip frame, subject, camera, room, noise) from its own generator; see "
       "doc/synthetic.md";
  info.provenance = p.str ();
  return info;
}

std::string
synthFrameId (std::uint64_t index)
{
  std::ostringstream out;
  out << std::setw (6) << std::setfill ('0') << index;
  return out.str ();
}

SynthRunStats
writeSyntheticDataset (const SynthGenerator &generator, int frames, const std::string &output, bool overwrite,
                       const std::function<void (int, int)> &progress)
{
  if (frames < 1)
    throw std::invalid_argument ("the number of frames must be at least 1");
  DatasetWriter writer (output, generator.datasetInfo (), overwrite);
  SynthRunStats stats;
  using clock = std::chrono::steady_clock;
  for (int i = 0; i < frames; ++i)
  {
    const auto t0 = clock::now ();
    const SynthFrame frame = generator.render (static_cast<std::uint64_t> (i));
    const auto t1 = clock::now ();
    const std::string id = synthFrameId (static_cast<std::uint64_t> (i));
    if (frame.colour.empty ())
      writer.addFrame (id, frame.sequence, frame.cloud, frame.labels);
    else
    {
      pcl::PointCloud<pcl::PointXYZRGBA> coloured;
      pcl::copyPointCloud (frame.cloud, coloured);
      for (std::size_t p = 0; p < coloured.size (); ++p)
      {
        coloured[p].r = frame.colour[p][0];
        coloured[p].g = frame.colour[p][1];
        coloured[p].b = frame.colour[p][2];
        coloured[p].a = 255;
      }
      writer.addFrame (id, frame.sequence, coloured, frame.labels);
    }
    const int w = generator.sensor ().width, h = generator.sensor ().height;
    // cv::Mat views of the frame's own buffers (not written to).
    writer.addPartLabels (id, cv::Mat (h, w, CV_8UC1, const_cast<std::uint8_t *> (frame.part_label.data ())));
    writer.addPersonLabels (id, cv::Mat (h, w, CV_8UC1, const_cast<std::uint8_t *> (frame.person_label.data ())));
    const auto t2 = clock::now ();
    stats.render_ms += std::chrono::duration<double, std::milli> (t1 - t0).count ();
    stats.write_ms += std::chrono::duration<double, std::milli> (t2 - t1).count ();
    ++stats.frames;
    for (const auto &l : frame.labels)
    {
      ++stats.labels;
      stats.visible_labels += l.visible ? 1 : 0;
    }
    if (progress)
      progress (i + 1, frames);
  }
  writer.commit ();
  return stats;
}
}  // namespace agex
