// Body shapes: MakeHuman's macro variables (agex::BodyShape), their targets blended as
// MakeHuman 1.1 blends them (agex::MakeHumanTargets), the mesh and skeleton shaped by them
// (HumanMesh::shaped), posed shaped bodies and the generator's per-subject shapes.

#include "test_support.h"

#include <agex/simulation/body_shape.h>
#include <agex/simulation/human_mesh.h>
#include <agex/simulation/make_human_targets.h>
#include <agex/simulation/synthetic_scene.h>

#include <algorithm>
#include <cstdio>
#include <map>

namespace
{
using agex_test::sharedData;
namespace fs = std::filesystem;

#define AGEX_REQUIRE_MAKEHUMAN_TARGETS()                                                                  \
  do                                                                                                      \
  {                                                                                                       \
    AGEX_REQUIRE_SHARED_FILE (sharedData ("makehuman/default_weights.mhw"),                               \
                              "the MakeHuman body mesh (../shared/data/makehuman)");                      \
    AGEX_REQUIRE_SHARED_FILE (sharedData ("makehuman/targets/macrodetails/height"),                       \
                              "MakeHuman's macro targets (../shared/data/makehuman/targets/macrodetails)"); \
  } while (0)

/** The base mesh and its targets, loaded once (about a second). */
struct Assets
{
  agex::HumanMesh base;
  agex::MakeHumanTargets targets;
};
const Assets &
assets ()
{
  static const Assets loaded = [] {
    agex::HumanMesh base = agex::HumanMesh::load (sharedData ("makehuman"));
    agex::MakeHumanTargets targets = agex::MakeHumanTargets::load (sharedData ("makehuman"), base.baseVertexCount ());
    return Assets{std::move (base), std::move (targets)};
  }();
  return loaded;
}

agex::BodyShape
tallHeavyMale ()
{
  agex::BodyShape s;
  s.gender = 1.0;
  s.age = agex::BodyShape::ageFromYears (30.0);
  s.muscle = 0.5;
  s.weight = 1.0;
  s.height = 0.68;  // about 2 m
  return s;
}

agex::BodyShape
shortSlimFemale ()
{
  agex::BodyShape s;
  s.gender = 0.0;
  s.age = agex::BodyShape::ageFromYears (30.0);
  s.muscle = 0.5;
  s.weight = 0.0;
  s.height = 0.38;  // about 1.5 m
  return s;
}

/** Perimeter of the convex hull of points in a plane (monotone chain). */
double
hullPerimeter (std::vector<Eigen::Vector2d> p)
{
  if (p.size () < 3)
    return 0.0;
  std::sort (p.begin (), p.end (), [] (const Eigen::Vector2d &a, const Eigen::Vector2d &b) {
    return a.x () < b.x () || (a.x () == b.x () && a.y () < b.y ());
  });
  auto cross = [] (const Eigen::Vector2d &o, const Eigen::Vector2d &a, const Eigen::Vector2d &b) {
    return (a.x () - o.x ()) * (b.y () - o.y ()) - (a.y () - o.y ()) * (b.x () - o.x ());
  };
  std::vector<Eigen::Vector2d> hull (2 * p.size ());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size (); ++i)
  {
    while (k >= 2 && cross (hull[k - 2], hull[k - 1], p[i]) <= 0)
      --k;
    hull[k++] = p[i];
  }
  for (std::size_t i = p.size () - 1, t = k + 1; i > 0; --i)
  {
    while (k >= t && cross (hull[k - 2], hull[k - 1], p[i - 1]) <= 0)
      --k;
    hull[k++] = p[i - 1];
  }
  double perimeter = 0.0;
  for (std::size_t i = 0; i + 1 < k; ++i)
    perimeter += (hull[i + 1] - hull[i]).norm ();
  return perimeter;
}

/** Girth of a body part around a horizontal slice at height y (a tape measure's
  * length: the slice's convex hull), from the part's vertices within 1.5 cm of it. */
double
girth (const agex::HumanMesh &mesh, agex::HumanMesh::Part part, double y)
{
  std::vector<Eigen::Vector2d> slice;
  for (std::size_t v = 0; v < mesh.vertices ().size (); ++v)
    if (mesh.parts ()[v] == part && std::abs (mesh.vertices ()[v].y () - y) < 0.015)
      slice.emplace_back (mesh.vertices ()[v].x (), mesh.vertices ()[v].z ());
  return hullPerimeter (slice);
}

const Eigen::Vector3d &
jointOf (const agex::HumanMesh &mesh, const std::string &bone)
{
  return mesh.bones ()[static_cast<std::size_t> (mesh.bone (bone))].head;
}

/** Measures of a body: standing height, waist (trunk at the spine03 joint: the
  * natural waist above the navel), hips (trunk at the hip joints), thigh (left leg half
  * way from hip to knee), shoulder width (X extent of the trunk). */
struct Measures
{
  double height, waist, hips, thigh, shoulders;
};
Measures
measure (const agex::HumanMesh &mesh)
{
  Measures m;
  m.height = mesh.height ();
  m.waist = girth (mesh, agex::HumanMesh::Trunk, jointOf (mesh, "spine03").y ());
  m.hips = girth (mesh, agex::HumanMesh::Trunk, jointOf (mesh, "upperleg01.L").y ());
  m.thigh = girth (mesh, agex::HumanMesh::LeftLeg,
                   0.5 * (jointOf (mesh, "upperleg01.L").y () + jointOf (mesh, "lowerleg01.L").y ()));
  double lo = 1e9, hi = -1e9;
  for (std::size_t v = 0; v < mesh.vertices ().size (); ++v)
    if (mesh.parts ()[v] == agex::HumanMesh::Trunk)
    {
      lo = std::min (lo, mesh.vertices ()[v].x ());
      hi = std::max (hi, mesh.vertices ()[v].x ());
    }
  m.shoulders = hi - lo;
  return m;
}

TEST (BodyShape, RangesAreChecked)
{
  EXPECT_TRUE (agex::BodyShape ().valid ()) << agex::BodyShape ().problem ();
  EXPECT_NEAR (agex::BodyShape ().ageYears (), 25.0, 1e-9);
  EXPECT_NEAR (agex::BodyShape::ageFromYears (57.5), 0.75, 1e-12);
  EXPECT_NEAR (agex::BodyShape::ageFromYears (13.0), 0.25, 1e-12);
  struct Case
  {
    std::function<void (agex::BodyShape &)> change;
    const char *named;
  };
  const Case cases[] = {{[] (agex::BodyShape &s) { s.gender = 1.5; }, "gender"},
                        {[] (agex::BodyShape &s) { s.weight = std::nan (""); }, "weight"},
                        {[] (agex::BodyShape &s) { s.height = -0.1; }, "height"},
                        {[] (agex::BodyShape &s) { s.muscle = std::numeric_limits<double>::infinity (); }, "muscle"},
                        {[] (agex::BodyShape &s) { s.age = agex::BodyShape::ageFromYears (18.0); }, "25 years"},
                        {[] (agex::BodyShape &s) { s.asian = 0.0; }, "must be 1"}};
  for (const Case &c : cases)
  {
    agex::BodyShape shape;
    c.change (shape);
    EXPECT_FALSE (shape.valid ());
    EXPECT_NE (shape.problem ().find (c.named), std::string::npos) << shape.problem ();
  }
  // Samples: valid, within the documented ranges, both genders, deterministic.
  agex::SynthRng rng (7), again (7);
  int male = 0;
  for (int i = 0; i < 1000; ++i)
  {
    const agex::BodyShape s = agex::BodyShape::sample (rng), t = agex::BodyShape::sample (again);
    ASSERT_TRUE (s.valid ()) << s.problem ();
    EXPECT_EQ (s.describe (), t.describe ());
    EXPECT_TRUE (s.gender <= 0.15 || s.gender >= 0.85) << s.describe ();
    male += s.gender > 0.5;
    EXPECT_GE (s.ageYears (), 25.0 - 1e-9);
    EXPECT_LE (s.ageYears (), 70.0 + 1e-9);
    EXPECT_GE (s.weight, 0.05);
    EXPECT_LE (s.weight, 0.95);
  }
  EXPECT_GT (male, 430);
  EXPECT_LT (male, 570);
}

TEST (MakeHumanTargets, WeightsAreMakeHumansProducts)
{
  AGEX_REQUIRE_MAKEHUMAN_TARGETS ();
  const agex::MakeHumanTargets &targets = assets ().targets;
  ASSERT_EQ (targets.targets ().size (), 12u + 36u + 72u);
  agex::BodyShape s;
  s.gender = 0.8;
  s.age = 0.75;
  s.muscle = 0.25;
  s.weight = 0.9;
  s.height = 0.3;
  s.african = 0.2;
  s.asian = 0.5;
  s.caucasian = 0.3;
  using T = agex::MakeHumanTargets;
  EXPECT_NEAR (T::factor ("male", s), 0.8, 1e-12);
  EXPECT_NEAR (T::factor ("female", s), 0.2, 1e-12);
  EXPECT_NEAR (T::factor ("old", s), 0.5, 1e-12);
  EXPECT_NEAR (T::factor ("young", s), 0.5, 1e-12);
  EXPECT_NEAR (T::factor ("minmuscle", s), 0.5, 1e-12);
  EXPECT_NEAR (T::factor ("averagemuscle", s), 0.5, 1e-12);
  EXPECT_NEAR (T::factor ("maxmuscle", s), 0.0, 1e-12);
  EXPECT_NEAR (T::factor ("maxweight", s), 0.8, 1e-12);
  EXPECT_NEAR (T::factor ("averageweight", s), 0.2, 1e-12);
  EXPECT_NEAR (T::factor ("minheight", s), 0.4, 1e-12);
  EXPECT_THROW (T::factor ("tall", s), agex::HumanMeshError);
  // Per group, the weights of a full set of categories sum to that of the missing ones:
  // ethnic x gender x age and gender x age x muscle x weight to 1; the height targets
  // (no average height target) to minheight + maxheight.
  const std::vector<double> w = targets.weights (s);
  std::map<std::string, double> sum;
  for (std::size_t t = 0; t < w.size (); ++t)
  {
    sum[targets.targets ()[t].group] += w[t];
    const std::string name = fs::path (targets.targets ()[t].file).stem ().string ();
    if (name == "universal-male-old-minmuscle-maxweight")
    {
      EXPECT_NEAR (w[t], 0.8 * 0.5 * 0.5 * 0.8, 1e-12);
    }
    if (name == "asian-female-young")
    {
      EXPECT_NEAR (w[t], 0.5 * 0.2 * 0.5, 1e-12);
    }
    if (name == "male-old-averagemuscle-averageweight-minheight")
    {
      EXPECT_NEAR (w[t], 0.8 * 0.5 * 0.5 * 0.2 * 0.4, 1e-12);
    }
  }
  EXPECT_NEAR (sum["macrodetails"], 1.0, 1e-12);
  EXPECT_NEAR (sum["macrodetails-universal"], 1.0, 1e-12);
  EXPECT_NEAR (sum["macrodetails-height"], 0.4, 1e-12);
  agex::BodyShape young;
  young.age = 0.3;
  EXPECT_THROW (targets.weights (young), agex::HumanMeshError);
}

TEST (HumanMeshShape, DefaultShapeIsNearTheBaseMesh)
{
  AGEX_REQUIRE_MAKEHUMAN_TARGETS ();
  const agex::HumanMesh &base = assets ().base;
  EXPECT_FALSE (base.isShaped ());
  const agex::HumanMesh shaped = base.shaped (assets ().targets, agex::BodyShape ());
  EXPECT_TRUE (shaped.isShaped ());
  ASSERT_EQ (shaped.vertices ().size (), base.vertices ().size ());
  // MakeHuman's default human (every slider in the middle) is not base.obj as it is: it
  // adds a sixth of each young ethnic target (the universal average targets are empty,
  // no height target is used). Those weights, and only they:
  const std::vector<double> w = assets ().targets.weights (agex::BodyShape ());
  for (std::size_t t = 0; t < w.size (); ++t)
  {
    const auto &target = assets ().targets.targets ()[t];
    const std::string name = fs::path (target.file).stem ().string ();
    const bool ethnic_young = target.group == "macrodetails" && name.find ("young") != std::string::npos;
    const bool empty_average = name.find ("averagemuscle-averageweight") != std::string::npos &&
                               name.find ("young") != std::string::npos && target.group == "macrodetails-universal";
    if (ethnic_young)
      EXPECT_NEAR (w[t], 1.0 / 6.0, 1e-12) << name;
    else if (empty_average)
      EXPECT_TRUE (target.vertices.empty ()) << name;
    else
      EXPECT_EQ (w[t], 0.0) << name;
  }
  // They reshape the body by centimetres (base.obj is the neutral mesh MakeHuman's
  // targets start from, not its default human) but keep its stature within a centimetre.
  // Measured after removing the mean move (the ethnic targets lower the body a little):
  Eigen::Vector3d shift = Eigen::Vector3d::Zero ();
  for (std::size_t v = 0; v < base.vertices ().size (); ++v)
    shift += shaped.vertices ()[v] - base.vertices ()[v];
  shift /= static_cast<double> (base.vertices ().size ());
  std::printf ("default shape: mean move %.4f %.4f %.4f m\n", shift.x (), shift.y (), shift.z ());
  std::vector<double> moves;
  for (std::size_t v = 0; v < base.vertices ().size (); ++v)
    moves.push_back ((shaped.vertices ()[v] - base.vertices ()[v] - shift).norm ());
  std::sort (moves.begin (), moves.end ());
  double joint_median = 0.0;
  {
    std::vector<double> joints;
    for (std::size_t b = 0; b < base.bones ().size (); ++b)
      joints.push_back ((shaped.bones ()[b].head - base.bones ()[b].head - shift).norm ());
    std::sort (joints.begin (), joints.end ());
    joint_median = joints[joints.size () / 2];
  }
  std::printf ("default shape against base.obj: vertex moves median %.4f, 95%% %.4f, largest %.4f m; joints "
               "median %.4f m; height %.4f vs %.4f m\n",
               moves[moves.size () / 2], moves[moves.size () * 95 / 100], moves.back (), joint_median,
               shaped.height (), base.height ());
  EXPECT_LT (moves[moves.size () / 2], 0.04);
  EXPECT_LT (moves.back (), 0.10);
  EXPECT_LT (joint_median, 0.05);
  EXPECT_NEAR (shaped.height (), base.height (), 0.01);
  // Shaping starts from base.obj whatever the body's shape: shaping twice is shaping once.
  const agex::HumanMesh twice = shaped.shaped (assets ().targets, tallHeavyMale ());
  const agex::HumanMesh once = base.shaped (assets ().targets, tallHeavyMale ());
  for (std::size_t v = 0; v < once.vertices ().size (); v += 97)
    EXPECT_EQ (twice.vertices ()[v], once.vertices ()[v]);
  // load (directory, shape) gives the same body.
  const agex::HumanMesh loaded = agex::HumanMesh::load (sharedData ("makehuman"), tallHeavyMale ());
  EXPECT_EQ (loaded.height (), once.height ());
  EXPECT_THROW (base.shaped (assets ().targets, agex::BodyShape{2.0}), agex::HumanMeshError);
}

TEST (HumanMeshShape, TallHeavyMaleAndShortSlimFemaleDiffer)
{
  AGEX_REQUIRE_MAKEHUMAN_TARGETS ();
  const agex::HumanMesh big = assets ().base.shaped (assets ().targets, tallHeavyMale ());
  const agex::HumanMesh small = assets ().base.shaped (assets ().targets, shortSlimFemale ());
  const Measures b = measure (big), s = measure (small), d = measure (assets ().base);
  std::printf ("            height  waist  hips  thigh  shoulders (m)\n");
  for (const auto &[name, m] : {std::pair<const char *, Measures> ("tall heavy male", b), {"short slim female", s},
                                {"base.obj", d}})
    std::printf ("%-18s %.3f  %.3f  %.3f  %.3f  %.3f\n", name, m.height, m.waist, m.hips, m.thigh, m.shoulders);
  // MakeHuman's extremes: its height slider spans about 1.5-2.0 m for these bodies.
  EXPECT_GT (b.height, 1.90);
  EXPECT_LT (b.height, 2.15);
  EXPECT_GT (s.height, 1.35);
  EXPECT_LT (s.height, 1.60);
  EXPECT_GT (b.height - s.height, 0.40);
  // Girth: a heavy man's waist is far larger than a slim woman's (MakeHuman's "150%"
  // against "50%" weight); thighs and shoulders too.
  EXPECT_GT (b.waist, 1.4 * s.waist);
  EXPECT_GT (b.thigh, 1.4 * s.thigh);
  EXPECT_GT (b.shoulders, 1.2 * s.shoulders);
  EXPECT_GT (b.waist, 0.9);
  EXPECT_LT (s.waist, 0.75);
  // The skeleton follows the mesh: the head and knee joints scale with stature.
  auto sole = [] (const agex::HumanMesh &mesh) {
    double lowest = 1e9;
    for (const auto &v : mesh.vertices ())
      lowest = std::min (lowest, v.y ());
    return lowest;
  };
  for (const char *bone : {"head", "neck01", "lowerleg01.L"})
  {
    const double ratio = (jointOf (big, bone).y () - sole (big)) / (jointOf (small, bone).y () - sole (small));
    std::printf ("%s joint above the soles: %.3f vs %.3f m (ratio %.3f, statures %.3f)\n", bone,
                 jointOf (big, bone).y () - sole (big), jointOf (small, bone).y () - sole (small), ratio,
                 b.height / s.height);
    // MakeHuman's height targets lengthen the legs a little more than the trunk.
    EXPECT_NEAR (ratio, b.height / s.height, (bone[0] == 'l' ? 0.1 : 0.05) * b.height / s.height) << bone;
  }
  // Each joint lies within its body: the head joint below the top of the head.
  EXPECT_LT (jointOf (big, "head").y (), big.vertices ()[static_cast<std::size_t> (
                                             big.tipVertices ()[agex::HumanMesh::Head])].y ());
}

/** The largest stretch of a posed edge over its rest length (plus 5 mm). */
double
largestStretch (const agex::HumanMesh &mesh, const agex::BodyModel &body, double scale, double &stretched_twice)
{
  double worst = 0.0;
  long edges = 0, stretched = 0;
  for (int part = 0; part < agex::HumanMesh::kParts; ++part)
  {
    const auto &posed = *body.primitives[static_cast<std::size_t> (part)].mesh;
    std::size_t k = 0;
    for (std::size_t t = 0; t < mesh.triangles ().size (); ++t)
    {
      if (mesh.triangleParts ()[t] != part)
        continue;
      const Eigen::Vector3i &rest = mesh.triangles ()[t], &now = posed.triangles ()[k++];
      for (int e = 0; e < 3; ++e)
      {
        const double before = (mesh.vertices ()[static_cast<std::size_t> (rest[e])] -
                               mesh.vertices ()[static_cast<std::size_t> (rest[(e + 1) % 3])]).norm ();
        const double after = (posed.vertices ()[static_cast<std::size_t> (now[e])] -
                              posed.vertices ()[static_cast<std::size_t> (now[(e + 1) % 3])]).norm ();
        const double stretch = after / (scale * before + 0.005);
        worst = std::max (worst, stretch);
        ++edges;
        stretched += stretch > 2.0;
      }
    }
  }
  stretched_twice = static_cast<double> (stretched) / static_cast<double> (std::max (edges, 1L));
  return worst;
}

TEST (HumanMeshShape, ShapedBodiesSkinCleanlyInExtremePoses)
{
  AGEX_REQUIRE_MAKEHUMAN_TARGETS ();
  AGEX_REQUIRE_SHARED_FILE (sharedData ("mocap/cmu_05_06.bvh"), "the CMU motion capture (../shared/data/mocap)");
  const agex::MotionClip clip = agex::MotionClip::load (sharedData ("mocap/cmu_05_06.bvh"));
  const agex::BodyParams params;
  for (const agex::BodyShape &shape : {tallHeavyMale (), shortSlimFemale ()})
  {
    const agex::HumanMesh mesh = assets ().base.shaped (assets ().targets, shape);
    // The dance's most extreme frames: hands highest, hands widest apart, feet widest apart.
    int high = 0, wide = 0, stride = 0;
    double best_high = -1e9, best_wide = -1e9, best_stride = -1e9;
    std::vector<Eigen::Isometry3d> g;
    for (int f = 0; f < clip.motion.frameCount (); f += 5)
    {
      clip.motion.pose (f, clip.scale, g);
      auto P = [&] (int j) { return g[static_cast<std::size_t> (j)].translation (); };
      const auto &m = clip.map;
      const double h = std::max (P (m.wrist[0]).y (), P (m.wrist[1]).y ()) - P (m.root).y ();
      const double w = (P (m.wrist[0]) - P (m.wrist[1])).norm (), st = (P (m.ankle[0]) - P (m.ankle[1])).norm ();
      if (h > best_high) best_high = h, high = f;
      if (w > best_wide) best_wide = w, wide = f;
      if (st > best_stride) best_stride = st, stride = f;
    }
    const agex::BodyModel rest = agex::buildMeshBody (clip, -1, params, mesh);
    // Posed at its own size: the rest body is as tall as the shaped mesh.
    // (The clip's rest pose stands the feet and head a little unlike MakeHuman's.)
    EXPECT_NEAR (rest.highest - rest.lowest, mesh.height (), 0.05 * mesh.height ()) << shape.describe ();
    for (const int frame : {high, wide, stride})
    {
      const agex::BodyModel body = agex::buildMeshBody (clip, frame, params, mesh);
      const std::string at = shape.describe () + " frame " + std::to_string (frame);
      Eigen::Vector3d lo = Eigen::Vector3d::Constant (1e9), hi = -lo;
      for (const auto &primitive : body.primitives)
        for (const auto &v : primitive.mesh->vertices ())
        {
          ASSERT_TRUE (v.allFinite ()) << at;
          lo = lo.cwiseMin (v);
          hi = hi.cwiseMax (v);
          // Nothing flies off: every vertex within a stature of the torso's centre.
          ASSERT_LT ((v - body.centre).norm (), mesh.height ()) << at;
        }
      const Eigen::Vector3d extent = hi - lo;
      EXPECT_LT (extent.maxCoeff (), 1.3 * mesh.height ()) << at;
      EXPECT_GT (extent.maxCoeff (), 0.5 * mesh.height ()) << at;
      // Skinning tears no more than today's unshaped mesh does in the same frame (linear
      // blend skinning stretches the armpits when the arms are raised): the largest
      // stretch of an edge over its rest length within 1.6 times the unshaped body's,
      // and under 0.5% of the edges stretched to twice their length.
      double twice = 0.0, base_twice = 0.0;
      const double stretch = largestStretch (mesh, body, 1.0, twice);
      const agex::BodyModel base_body = agex::buildMeshBody (clip, frame, params, assets ().base);
      const double base_stretch = largestStretch (
          assets ().base, base_body, agex::restStandingHeight (clip) / assets ().base.height (), base_twice);
      std::printf ("%s: extent %.2f x %.2f x %.2f m, largest edge stretch %.2f (unshaped %.2f), edges stretched "
                   "twice %.3f%% (unshaped %.3f%%)\n",
                   at.c_str (), extent.x (), extent.y (), extent.z (), stretch, base_stretch, 100.0 * twice,
                   100.0 * base_twice);
      EXPECT_LT (stretch, 1.6 * base_stretch) << at;
      EXPECT_LT (twice, 0.005) << at;
    }
  }
}

TEST (HumanMeshShape, SampledShapesSpanTheAdultRange)
{
  AGEX_REQUIRE_MAKEHUMAN_TARGETS ();
  agex::SynthRng rng (2024);
  const int n = 1000;
  std::vector<double> heights, waists, hips, thighs, shoulders;
  int male = 0;
  std::vector<double> male_heights, female_heights;
  for (int i = 0; i < n; ++i)
  {
    const agex::BodyShape shape = agex::BodyShape::sample (rng);
    const Measures m = measure (assets ().base.shaped (assets ().targets, shape));
    heights.push_back (m.height);
    waists.push_back (m.waist);
    hips.push_back (m.hips);
    thighs.push_back (m.thigh);
    shoulders.push_back (m.shoulders);
    (shape.gender > 0.5 ? male_heights : female_heights).push_back (m.height);
    male += shape.gender > 0.5;
  }
  auto quantile = [] (std::vector<double> v, double q) {
    std::sort (v.begin (), v.end ());
    return v[static_cast<std::size_t> (q * static_cast<double> (v.size () - 1) + 0.5)];
  };
  std::printf ("%d sampled shapes (%d male), metres: min / 5%% / median / 95%% / max\n", n, male);
  for (const auto &[name, v] : {std::pair<const char *, const std::vector<double> *> ("height", &heights),
                                {"height (men)", &male_heights}, {"height (women)", &female_heights},
                                {"waist", &waists}, {"hips", &hips}, {"thigh", &thighs}, {"shoulders", &shoulders}})
    std::printf ("%-15s %.3f / %.3f / %.3f / %.3f / %.3f\n", name, quantile (*v, 0.0), quantile (*v, 0.05),
                 quantile (*v, 0.5), quantile (*v, 0.95), quantile (*v, 1.0));
  EXPECT_GT (quantile (heights, 0.0), 1.40);
  EXPECT_LT (quantile (heights, 1.0), 2.05);
  EXPECT_LT (quantile (heights, 0.05), 1.58);
  EXPECT_GT (quantile (heights, 0.95), 1.80);
  EXPECT_GT (quantile (male_heights, 0.5), quantile (female_heights, 0.5) + 0.08);
  EXPECT_GT (quantile (waists, 0.95), 1.25 * quantile (waists, 0.05)) << "slim to heavy";
}

TEST (MakeHumanTargets, BadTargetFilesAreRefused)
{
  AGEX_REQUIRE_MAKEHUMAN_TARGETS ();
  const fs::path source = sharedData ("makehuman");
  const std::size_t vertices = assets ().base.baseVertexCount ();
  // A small MakeHuman directory: the modifiers and one target of each group.
  const fs::path dir = fs::temp_directory_path () / ("agex_body_shape_" + std::to_string (::getpid ()));
  fs::remove_all (dir);
  fs::create_directories (dir / "modifiers");
  fs::create_directories (dir / "targets/macrodetails/height");
  fs::copy_file (source / "modifiers/modeling_modifiers.json", dir / "modifiers/modeling_modifiers.json");
  const fs::path ethnic = dir / "targets/macrodetails/caucasian-male-young.target";
  fs::copy_file (source / "targets/macrodetails/caucasian-male-young.target", ethnic);
  fs::copy_file (source / "targets/macrodetails/universal-male-young-maxmuscle-maxweight.target",
                 dir / "targets/macrodetails/universal-male-young-maxmuscle-maxweight.target");
  fs::copy_file (source / "targets/macrodetails/height/male-young-averagemuscle-averageweight-maxheight.target",
                 dir / "targets/macrodetails/height/male-young-averagemuscle-averageweight-maxheight.target");
  const agex::MakeHumanTargets small = agex::MakeHumanTargets::load (dir.string (), vertices);
  EXPECT_EQ (small.targets ().size (), 3u);
  const std::string good = agex_test::readAll (ethnic.string ());
  long comment_lines = 0;
  {
    std::istringstream in (good);
    std::string line;
    while (std::getline (in, line) && (line.empty () || line[0] == '#'))
      ++comment_lines;
  }
  auto expectRefused = [&] (const std::string &first_data_line, const std::string &expected, long line = 1) {
    const std::string bad_line = std::to_string (comment_lines + line);
    agex_test::writeAll (ethnic.string (), good.substr (0, good.find ("\n0 ") + 1) + first_data_line + "\n");
    try
    {
      agex::MakeHumanTargets::load (dir.string (), vertices);
      ADD_FAILURE () << "accepted '" << first_data_line << "'";
    }
    catch (const agex::HumanMeshError &e)
    {
      const std::string what = e.what ();
      EXPECT_NE (what.find (ethnic.string () + ":" + bad_line + ":"), std::string::npos) << what;
      EXPECT_NE (what.find (expected), std::string::npos) << what;
    }
  };
  expectRefused ("19158 0 0 0", "not one of the base mesh's 19158");
  expectRefused ("-1 0 0 0", "not one of");
  expectRefused ("5 0 nan 0", "finite");
  expectRefused ("5 0 1e300 0", "finite");
  expectRefused ("5 0 0", "expected 'vertex dx dy dz'");
  expectRefused ("5 0 0 0 7", "nothing after it");
  expectRefused ("5 0 0 0\n5 1 1 1", "listed twice", 2);
  expectRefused ("x 0 0 0", "expected");
  // A target whose name puts it in no macro group, and a missing group.
  agex_test::writeAll (ethnic.string (), good);
  agex_test::writeAll ((dir / "targets/macrodetails/tall-male.target").string (), "0 0 0 0\n");
  try
  {
    agex::MakeHumanTargets::load (dir.string (), vertices);
    ADD_FAILURE () << "accepted a target of group macrodetails-tall";
  }
  catch (const agex::HumanMeshError &e)
  {
    EXPECT_NE (std::string (e.what ()).find ("group 'macrodetails-tall'"), std::string::npos) << e.what ();
  }
  fs::remove (dir / "targets/macrodetails/tall-male.target");
  fs::remove_all (dir / "targets/macrodetails/height");
  EXPECT_THROW (agex::MakeHumanTargets::load (dir.string (), vertices), agex::HumanMeshError);
  // Targets of another mesh.
  fs::create_directories (dir / "targets/macrodetails/height");
  fs::copy_file (source / "targets/macrodetails/height/male-young-averagemuscle-averageweight-maxheight.target",
                 dir / "targets/macrodetails/height/male-young-averagemuscle-averageweight-maxheight.target");
  const agex::MakeHumanTargets other = agex::MakeHumanTargets::load (dir.string (), vertices + 5);
  EXPECT_THROW (assets ().base.shaped (other, agex::BodyShape ()), agex::HumanMeshError);
  fs::remove_all (dir);
}

TEST (SynthGeneratorShapes, EachSubjectHasItsOwnShapedMesh)
{
  AGEX_REQUIRE_MAKEHUMAN_TARGETS ();
  AGEX_REQUIRE_SHARED_FILE (sharedData ("mocap/cmu_131_03.bvh"), "the CMU motion capture (../shared/data/mocap)");
  agex::SynthOptions options;
  options.motion_files = {sharedData ("mocap/cmu_131_03.bvh")};
  options.subjects = 3;
  options.body_shapes = true;
  EXPECT_THROW (agex::SynthGenerator{options}, std::invalid_argument) << "shapes need a mesh";
  options.body_mesh = sharedData ("makehuman");
  const agex::SynthGenerator gen (options);
  ASSERT_EQ (gen.shapes ().size (), 3u);
  std::set<double> heights;
  for (int s = 0; s < 3; ++s)
  {
    const agex::HumanMesh *mesh = gen.mesh (s);
    ASSERT_NE (mesh, nullptr);
    EXPECT_TRUE (mesh->isShaped ());
    EXPECT_EQ (mesh->shape ().describe (), gen.shapes ()[static_cast<std::size_t> (s)].describe ());
    heights.insert (mesh->height ());
    // The body is as tall as its shape: BodyParams' height_scale no longer sets it.
    const agex::BodyModel body = gen.body (0, -1, s);
    EXPECT_NEAR (body.highest - body.lowest, mesh->height (), 0.05 * mesh->height ());
  }
  EXPECT_EQ (heights.size (), 3u);
  EXPECT_THROW (gen.mesh (3), std::out_of_range);
  EXPECT_NE (gen.datasetInfo ().provenance.find ("shape gender="), std::string::npos);
  // Frames stay a function of the options and the index.
  const agex::SynthGenerator again (options);
  const agex::SynthFrame a = gen.render (2), b = again.render (2);
  ASSERT_EQ (a.ideal_z.size (), b.ideal_z.size ());
  int person = 0;
  for (std::size_t i = 0; i < a.ideal_z.size (); ++i)
  {
    EXPECT_TRUE ((std::isnan (a.ideal_z[i]) && std::isnan (b.ideal_z[i])) || a.ideal_z[i] == b.ideal_z[i]);
    person += a.part_label[i] != 0;
  }
  EXPECT_GT (person, 100) << "the shaped person is in view";
  // Without shapes nothing changes: no shapes, the one mesh for everyone.
  options.body_shapes = false;
  const agex::SynthGenerator plain (options);
  EXPECT_TRUE (plain.shapes ().empty ());
  EXPECT_EQ (plain.mesh (1), plain.mesh ());
}
}  // namespace

namespace
{
/** Distances between the same vertices of two posings of one part (same triangles, same order). */
std::vector<double>
vertexMoves (const agex::SynthPrimitive &bare, const agex::SynthPrimitive &dressed)
{
  std::vector<double> moves;
  const auto &a = bare.mesh->vertices (), &b = dressed.mesh->vertices ();
  if (a.size () != b.size ())
    return moves;
  for (std::size_t v = 0; v < a.size (); ++v)
    moves.push_back ((b[v] - a[v]).norm ());
  return moves;
}
}  // namespace

TEST (SynthGeneratorClothes, DressedPartsMoveOutByTheirThicknessAndNothingElseChanges)
{
  AGEX_REQUIRE_MAKEHUMAN_TARGETS ();
  AGEX_REQUIRE_SHARED_FILE (sharedData ("mocap/cmu_131_03.bvh"), "the CMU motion capture (../shared/data/mocap)");
  agex::SynthOptions options;
  options.motion_files = {sharedData ("mocap/cmu_131_03.bvh")};
  options.subjects = 2;
  options.clothes = true;
  try
  {
    agex::SynthGenerator{options};
    ADD_FAILURE () << "clothes without a mesh were accepted";
  }
  catch (const std::invalid_argument &e)
  {
    EXPECT_NE (std::string (e.what ()).find ("clothes"), std::string::npos) << e.what ();
  }
  options.body_shapes = true;
  options.body_mesh = sharedData ("makehuman");
  const agex::SynthGenerator dressed (options);
  options.clothes = false;
  const agex::SynthGenerator bare (options);
  ASSERT_EQ (dressed.subjects ().size (), 2u);
  for (int s = 0; s < 2; ++s)
  {
    const agex::BodyParams &p = dressed.subjects ()[static_cast<std::size_t> (s)];
    const agex::BodyParams &q = bare.subjects ()[static_cast<std::size_t> (s)];
    EXPECT_FALSE (q.dressed ());
    ASSERT_TRUE (p.dressed ());
    EXPECT_TRUE (p.clothes_top >= 0.003 && p.clothes_top <= 0.025) << p.clothes_top;
    EXPECT_TRUE (p.shoes >= 0.008 && p.shoes <= 0.025) << p.shoes;
    EXPECT_TRUE (p.hair >= 0.0 && p.hair <= 0.03) << p.hair;
    // Clothes come from their own generator: the rest of the subject is drawn as without.
    EXPECT_EQ (p.describe ().rfind (q.describe (), 0), 0u) << p.describe () << " / " << q.describe ();
    EXPECT_NE (p.describe ().find (" shoes="), std::string::npos);

    const agex::BodyModel a = bare.body (0, 10, s), b = dressed.body (0, 10, s);
    ASSERT_EQ (a.primitives.size (), b.primitives.size ());
    const std::pair<agex::HumanMesh::Part, double> parts[] = {
        {agex::HumanMesh::LeftArm, p.clothes_top}, {agex::HumanMesh::RightLeg, p.clothes_bottom},
        {agex::HumanMesh::LeftFoot, p.shoes},      {agex::HumanMesh::RightHand, p.hands}};
    for (const auto &[part, thickness] : parts)
    {
      const std::vector<double> moves = vertexMoves (a.primitives[part], b.primitives[part]);
      ASSERT_FALSE (moves.empty ()) << "part " << part;
      // Every vertex a part owns moves by its thickness; seam vertices owned by a neighbour
      // move by the neighbour's.
      std::vector<double> sorted = moves;
      std::sort (sorted.begin (), sorted.end ());
      EXPECT_NEAR (sorted[sorted.size () / 2], thickness, 1e-6) << "part " << part;
    }
    // Hair: the top of the head rises by its thickness, the chin stays.
    EXPECT_NEAR ((b.tip[0] - a.tip[0]).norm (), p.hair, 1e-6);
    // Shoes lower the soles: the floor a frame stands the body on is below them.
    EXPECT_LT (b.lowest, a.lowest - 0.5 * p.shoes);
    // Dressed tips stand their part's thickness farther out: their visibility tolerance grows
    // by just that.
    const double thickness[5] = {p.hair, p.hands, p.hands, p.shoes, p.shoes};
    for (int t = 0; t < 5; ++t)
      EXPECT_NEAR (b.tip_tolerance[t] - a.tip_tolerance[t], thickness[t], 1e-9) << "tip " << t;
    // The floor search (meshBodyLowest, a sample of the vertices) finds the dressed soles
    // within a few millimetres of the dressed body's lowest point, and never above it by more.
    const double floor = agex::meshBodyLowest (dressed.clips ()[0], 10, p, *dressed.mesh (s));
    EXPECT_NEAR (floor, b.lowest, 0.005);
  }
  // Rendered frames of dressed people show more of them than bare ones.
  int bare_pixels = 0, dressed_pixels = 0;
  for (std::uint64_t i = 0; i < 3; ++i)
  {
    const agex::SynthFrame x = bare.render (i), y = dressed.render (i);
    for (std::size_t k = 0; k < x.part_label.size (); ++k)
    {
      bare_pixels += x.part_label[k] != 0;
      dressed_pixels += y.part_label[k] != 0;
    }
  }
  EXPECT_GT (bare_pixels, 300);
  EXPECT_GT (dressed_pixels, bare_pixels * 11 / 10) << bare_pixels << " bare, " << dressed_pixels << " dressed";
}
