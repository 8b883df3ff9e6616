// Synthetic frames (agex_synth): BVH parsing and forward kinematics against hand
// computed poses, real CMU clips of human size in both unit conventions, labels that
// project onto the rendered body, byte-identical datasets for a seed, the two sensor
// models (mixed pixels, noise growing with depth, disparity quantisation, edge holes)
// and bad BVH input.

#include "test_support.h"

#include <agex/simulation/bvh.h>
#include <agex/io/dataset.h>
#include <agex/simulation/human_mesh.h>
#include <agex/io/pcd_reader.h>
#include <agex/simulation/synth_mesh.h>
#include <agex/simulation/synthetic_scene.h>

#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <tuple>

namespace agex
{
/** Test names and messages show the sensor by name. */
inline void
PrintTo (SynthSensor sensor, std::ostream *out)
{
  *out << synthSensorName (sensor);
}
}  // namespace agex

namespace
{
using namespace agex_test;


// A three-joint chain with a different rotation order on each joint.
const char *kChain = R"(HIERARCHY
ROOT Root
{
	OFFSET 0 0 0
	CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
	JOINT Mid
	{
		OFFSET 0 2 0
		CHANNELS 3 Xrotation Yrotation Zrotation
		JOINT Tip
		{
			OFFSET 1 0 0
			CHANNELS 3 Yrotation Xrotation Zrotation
			End Site
			{
				OFFSET 0 0 3
			}
		}
	}
}
MOTION
Frames: 3
Frame Time: 0.1
0 0 0 0 0 0 0 0 0 0 0 0
1 2 3 90 90 0 0 0 0 0 0 0
0 0 0 0 0 0 90 90 0 0 0 0
)";

void
expectNear (const Eigen::Vector3d &actual, const Eigen::Vector3d &expected, const std::string &what)
{
  EXPECT_LT ((actual - expected).norm (), 1e-9) << what << ": got " << actual.transpose () << ", expected "
                                                << expected.transpose ();
}

/** Runs f, expecting an agex::BvhError whose message contains every needle. */
template <typename F>
void
expectBvhError (F &&f, const std::vector<std::string> &needles)
{
  try
  {
    f ();
    ADD_FAILURE () << "no agex::BvhError thrown";
  }
  catch (const agex::BvhError &e)
  {
    const std::string message = e.what ();
    for (const auto &needle : needles)
      EXPECT_NE (message.find (needle), std::string::npos) << "'" << needle << "' not in: " << message;
  }
  catch (const std::exception &e)
  {
    ADD_FAILURE () << "expected agex::BvhError, got another exception: " << e.what ();
  }
}

const std::vector<std::string> kMocap = {"cmu_131_01.bvh", "cmu_131_02.bvh", "cmu_131_03.bvh", "cmu_02_01.bvh",
                                         "cmu_05_06.bvh"};

#define AGEX_REQUIRE_MOCAP(path) AGEX_REQUIRE_SHARED_FILE (path, "the CMU motion capture (../shared/data/mocap)")

#define AGEX_REQUIRE_MAKEHUMAN()                                                                          \
  AGEX_REQUIRE_SHARED_FILE (sharedData ("makehuman/default_weights.mhw"),                                   \
                            "the MakeHuman body mesh (../shared/data/makehuman)")

/** Generators shared by the rendering tests (loading the clips costs ~0.1 s, the mesh
  * and its floor placement ~1 s); mesh: MakeHuman bodies instead of capsules. */
const agex::SynthGenerator &
generator (agex::SynthSensor sensor, bool mesh = false)
{
  static std::map<std::pair<int, bool>, std::unique_ptr<agex::SynthGenerator>> cache;
  auto &g = cache[{static_cast<int> (sensor), mesh}];
  if (!g)
  {
    agex::SynthOptions options;
    options.motion_files = {sharedData ("mocap/cmu_131_01.bvh"), sharedData ("mocap/cmu_02_01.bvh")};
    options.sensor = sensor;
    options.seed = 11;
    if (mesh)
      options.body_mesh = sharedData ("makehuman");
    g = std::make_unique<agex::SynthGenerator> (options);
  }
  return *g;
}

// ---------------------------------------------------------------------------
// BVH

TEST (SynthBvh, ForwardKinematicsOfAHandMadeChain)
{
  const agex::BvhMotion m = agex::BvhMotion::parse (kChain, "chain.bvh");
  ASSERT_EQ (m.joints ().size (), 4u);
  EXPECT_EQ (m.channelCount (), 12);
  EXPECT_EQ (m.frameCount (), 3);
  EXPECT_DOUBLE_EQ (m.frameTime (), 0.1);
  EXPECT_EQ (m.findJoint ("Tip"), 2);
  EXPECT_EQ (m.findJoint ("tip"), 2);
  EXPECT_EQ (m.findJoint ("Nope"), -1);
  EXPECT_TRUE (m.joints ()[3].end_site);
  EXPECT_EQ (m.joints ()[3].parent, 2);
  EXPECT_EQ (m.joints ()[2].first_channel, 9);
  EXPECT_EQ (m.joints ()[1].channels[0], agex::BvhChannel::Xrotation);
  EXPECT_DOUBLE_EQ (m.restHeight (), 2.0);

  std::vector<Eigen::Isometry3d> g;
  // Frame 0 is the rest pose: offsets accumulate.
  m.pose (0, 1.0, g);
  expectNear (g[1].translation (), {0, 2, 0}, "rest Mid");
  expectNear (g[2].translation (), {1, 2, 0}, "rest Tip");
  expectNear (g[3].translation (), {1, 2, 3}, "rest End Site");
  // Frame 1: root at (1,2,3), R = Rz(90) Rx(90) (file order). Rx(90) takes y to z,
  // z to -y; Rz(90) takes x to y, y to -x.
  m.pose (1, 1.0, g);
  expectNear (g[0].translation (), {1, 2, 3}, "root position");
  expectNear (g[1].translation (), {1, 2, 5}, "Mid = root + Rz Rx (0,2,0)");
  expectNear (g[2].translation (), {1, 3, 5}, "Tip = Mid + Rz Rx (1,0,0)");
  expectNear (g[3].translation (), {4, 3, 5}, "End = Tip + Rz Rx (0,0,3)");
  // Frame 2: Mid rotated Rx(90) Ry(90): Ry(90) takes x to -z, z to x.
  m.pose (2, 1.0, g);
  expectNear (g[2].translation (), {0, 3, 0}, "Tip = Mid + Rx Ry (1,0,0)");
  expectNear (g[3].translation (), {3, 3, 0}, "End = Tip + Rx Ry (0,0,3)");
  // The scale multiplies offsets and positions, not angles.
  m.pose (1, 0.5, g);
  expectNear (g[3].translation (), {2, 1.5, 2.5}, "scaled End Site");
  EXPECT_THROW (m.pose (3, 1.0, g), std::out_of_range);
}

TEST (SynthBvh, AutoScaleByRestHeight)
{
  std::string big = kChain;
  big.replace (big.find ("OFFSET 0 2 0"), 12, "OFFSET 0 20 0");  // 20 units tall: CMU units
  EXPECT_DOUBLE_EQ (agex::autoBvhScale (agex::BvhMotion::parse (kChain, "a.bvh")), 1.0);
  EXPECT_DOUBLE_EQ (agex::autoBvhScale (agex::BvhMotion::parse (big, "b.bvh")), agex::kCmuBvhUnit);
  big.replace (big.find ("OFFSET 0 20 0"), 13, "OFFSET 0 170 0");
  EXPECT_DOUBLE_EQ (agex::autoBvhScale (agex::BvhMotion::parse (big, "c.bvh")), 0.01);
}

TEST (SynthBvh, RealClipsAreHumanSizedInBothUnitConventions)
{
  for (const auto &name : kMocap)
  {
    const std::string path = sharedData ("mocap/" + name);
    AGEX_REQUIRE_MOCAP (path);
    const agex::MotionClip clip = agex::MotionClip::load (path);
    const bool cmu_units = name.rfind ("cmu_131", 0) != 0;
    EXPECT_DOUBLE_EQ (clip.scale, cmu_units ? agex::kCmuBvhUnit : 1.0) << name;
    EXPECT_EQ (clip.sequence, name.substr (0, name.size () - 4));
    EXPECT_GT (clip.motion.frameCount (), 300) << name;
    // Standing height of the body model in the rest pose, and of the skeleton.
    const double height = agex::restStandingHeight (clip);
    EXPECT_GT (height, 1.4) << name;
    EXPECT_LT (height, 2.1) << name;
    const double skeleton = clip.motion.restHeight () * clip.scale;
    EXPECT_GT (skeleton, 1.2) << name;
    EXPECT_LT (skeleton, 2.0) << name;
    // Posed frames: the head 0.5-2.0 m above the lower ankle (1.2 m or more when
    // standing: some clips crouch), the hands within arm's reach of the neck, the
    // limbs keep their lengths.
    std::vector<Eigen::Isometry3d> g;
    const agex::SkeletonMap &m = clip.map;
    double thigh0 = -1, tallest = 0;
    for (int f = 0; f < clip.motion.frameCount (); f += 37)
    {
      clip.motion.pose (f, clip.scale, g);
      auto P = [&] (int j) { return g[j].translation (); };
      const double head_above = P (m.head).y () - std::min (P (m.ankle[0]).y (), P (m.ankle[1]).y ());
      tallest = std::max (tallest, head_above);
      EXPECT_GT (head_above, 0.5) << name << " frame " << f;
      EXPECT_LT (head_above, 2.0) << name << " frame " << f;
      for (int s = 0; s < 2; ++s)
        EXPECT_LT ((P (m.wrist[s]) - P (m.neck)).norm (), 0.9) << name << " frame " << f;
      const double thigh = (P (m.knee[0]) - P (m.hip[0])).norm ();
      if (thigh0 < 0)
        thigh0 = thigh;
      EXPECT_NEAR (thigh, thigh0, 1e-9);
      EXPECT_GT (thigh, 0.3);
      EXPECT_LT (thigh, 0.55);
    }
    EXPECT_GT (tallest, 1.2) << name;
  }
  // An explicit scale gives the same as auto for a CMU-unit file.
  const std::string path = sharedData ("mocap/cmu_02_01.bvh");
  AGEX_REQUIRE_MOCAP (path);
  EXPECT_NEAR (agex::restStandingHeight (agex::MotionClip::load (path, agex::kCmuBvhUnit)),
               agex::restStandingHeight (agex::MotionClip::load (path)), 1e-12);
}

TEST (SynthBvh, BadInputNamesTheFileAndLine)
{
  TempDir dir;
  expectBvhError ([&] { agex::BvhMotion::read (dir.file ("missing.bvh")); }, {dir.file ("missing.bvh"), "cannot open"});
  expectBvhError ([&] { agex::MotionClip::load (dir.file ("missing.bvh")); }, {dir.file ("missing.bvh")});

  const std::string chain = kChain;
  auto parseFile = [&] (const std::string &name, const std::string &text) {
    writeAll (dir.file (name), text);
    return [&dir, name] { agex::BvhMotion::read (dir.file (name)); };
  };
  // Truncated inside the HIERARCHY (file ends in Tip's block).
  expectBvhError (parseFile ("cut.bvh", chain.substr (0, chain.find ("End Site"))),
                  {dir.file ("cut.bvh") + ":13:", "truncated"});
  // Truncated MOTION: a frame missing.
  expectBvhError (parseFile ("short.bvh", chain.substr (0, chain.rfind ("0 0 0 0 0 0 90"))),
                  {dir.file ("short.bvh"), "2 of 3 frames", "truncated"});
  // No MOTION at all.
  expectBvhError (parseFile ("nomotion.bvh", chain.substr (0, chain.find ("MOTION"))),
                  {dir.file ("nomotion.bvh"), "no MOTION"});
  // CHANNELS 6 with five names: line 5.
  {
    std::string bad = chain;
    bad.replace (bad.find (" Yrotation\n"), 10, "");
    expectBvhError (parseFile ("channels.bvh", bad), {dir.file ("channels.bvh") + ":6:", "CHANNELS 6", "lists 5"});
  }
  // CHANNELS 3 with four names.
  {
    std::string bad = chain;
    bad.replace (bad.find ("Xrotation Yrotation Zrotation"), 29, "Xrotation Yrotation Zrotation Xposition");
    expectBvhError (parseFile ("extra.bvh", bad), {dir.file ("extra.bvh") + ":9:", "more channel names"});
  }
  // A frame with the wrong number of values (line 25: the second frame).
  {
    std::string bad = chain;
    bad.replace (bad.find ("1 2 3 90 90 0 0 0 0 0 0 0"), 25, "1 2 3 90 90 0 0 0 0 0 0");
    expectBvhError (parseFile ("values.bvh", bad), {dir.file ("values.bvh") + ":25:", "11 values", "12 channels"});
  }
  // Not a number.
  {
    std::string bad = chain;
    bad.replace (bad.find ("OFFSET 1 0 0"), 12, "OFFSET 1 x 0");
    expectBvhError (parseFile ("nan.bvh", bad), {dir.file ("nan.bvh") + ":12:", "'x'"});
  }
  expectBvhError (parseFile ("empty.bvh", ""), {dir.file ("empty.bvh") + ":1:", "empty"});
  expectBvhError (parseFile ("text.bvh", "hello world\n"), {dir.file ("text.bvh") + ":1:", "HIERARCHY"});
  // A valid BVH without a human skeleton: the body model names what is missing.
  writeAll (dir.file ("chain.bvh"), chain);
  expectBvhError ([&] { agex::MotionClip::load (dir.file ("chain.bvh")); }, {dir.file ("chain.bvh"), "Head"});

  // Every truncation of a valid file parses or throws BvhError; nothing else.
  for (std::size_t n = 0; n < chain.size (); ++n)
  {
    try
    {
      agex::BvhMotion::parse (chain.substr (0, n), "cut.bvh");
    }
    catch (const agex::BvhError &)
    {
    }
    catch (const std::exception &e)
    {
      ADD_FAILURE () << "truncation at " << n << " threw a non-BvhError: " << e.what ();
    }
  }
}

// ---------------------------------------------------------------------------
// Random numbers

TEST (SynthRng, DeterministicUniformAndNormal)
{
  // std::mt19937_64 is fully specified: its 10000th output for the default seed.
  agex::SynthRng standard (5489u);
  for (int i = 0; i < 9999; ++i)
    standard.raw ();
  EXPECT_EQ (standard.raw (), 9981545732273789042ull);

  agex::SynthRng a = agex::SynthRng::forItem (3, 7), b = agex::SynthRng::forItem (3, 7), c = agex::SynthRng::forItem (3, 8);
  double sum = 0, sum2 = 0, lo = 1, hi = 0;
  const int n = 100000;
  bool differs = false;
  for (int i = 0; i < n; ++i)
  {
    const double x = a.normal ();
    ASSERT_EQ (x, b.normal ());
    differs = differs || x != c.normal ();
    sum += x;
    sum2 += x * x;
    const double u = a.uniform ();
    b.uniform ();
    c.uniform ();
    lo = std::min (lo, u);
    hi = std::max (hi, u);
  }
  EXPECT_TRUE (differs);
  EXPECT_NEAR (sum / n, 0.0, 0.02);
  EXPECT_NEAR (sum2 / n, 1.0, 0.02);
  EXPECT_GE (lo, 0.0);
  EXPECT_LT (hi, 1.0);
}

// ---------------------------------------------------------------------------
// Rendering and labels

/** A sensor model and a body: capsules (false) or the MakeHuman mesh (true). */
class SynthSensors : public ::testing::TestWithParam<std::tuple<agex::SynthSensor, bool>>
{
protected:
  agex::SynthSensor sensorKind () const { return std::get<0> (GetParam ()); }
  bool mesh () const { return std::get<1> (GetParam ()); }
};

#define AGEX_REQUIRE_BODY()  \
  do                         \
  {                          \
    if (mesh ())             \
      AGEX_REQUIRE_MAKEHUMAN (); \
  } while (0)

TEST_P (SynthSensors, LabelsProjectOntoTheRenderedBody)
{
  AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_131_01.bvh"));
  AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_02_01.bvh"));
  AGEX_REQUIRE_BODY ();
  const agex::SynthGenerator &gen = generator (sensorKind (), mesh ());
  const agex::SensorModel &sensor = gen.sensor ();
  const agex::CameraIntrinsics &k = sensor.intrinsics;
  const int frames = sensorKind () == agex::SynthSensor::Kinect ? 6 : 16;
  const int win = agex::labelWindow (sensor);
  int labels = 0, visible = 0;
  for (int f = 0; f < frames; ++f)
  {
    const agex::SynthFrame frame = gen.render (static_cast<std::uint64_t> (f));
    ASSERT_EQ (frame.labels.size (), 5u);
    ASSERT_EQ (frame.label_checks.size (), 5u);
    EXPECT_EQ (static_cast<int> (frame.cloud.width), sensor.width);
    EXPECT_EQ (static_cast<int> (frame.cloud.height), sensor.height);
    EXPECT_EQ (frame.labels[1].part, agex::BodyPart::Hand);
    EXPECT_LE (frame.labels[1].tip_px.x (), frame.labels[2].tip_px.x ()) << "hand 0 is on the image's left";
    EXPECT_LE (frame.labels[3].tip_px.x (), frame.labels[4].tip_px.x ()) << "foot 0 is on the image's left";
    for (std::size_t j = 0; j < frame.labels.size (); ++j)
    {
      const agex::PartLabel &l = frame.labels[j];
      const agex::SynthLabelCheck &check = frame.label_checks[j];
      const std::string where = "frame " + std::to_string (f) + " " + agex::bodyPartName (l.part) + " " +
                                std::to_string (l.instance);
      ++labels;
      EXPECT_TRUE (l.keyframe);
      // Tips on the surface of their own part of the body (the person, not the floor
      // or a wall; a hand may rest inside another part, a thigh say).
      const Eigen::Vector3d tip = l.tip.cast<double> ();
      double own = std::numeric_limits<double>::infinity ();
      for (const int p : check.primitives)
        own = std::min (own, std::abs (frame.scene.primitives.at (static_cast<std::size_t> (p)).distance (tip)));
      ASSERT_FALSE (check.primitives.empty ());
      EXPECT_EQ (frame.scene.primitives[static_cast<std::size_t> (check.primitives[0])].object,
                 agex::SynthObject::Person);
      EXPECT_LT (own, 0.002) << where;
      EXPECT_LT (frame.scene.distance (tip, agex::SynthObject::Person), 0.002) << where;
      EXPECT_GT (frame.scene.distance (tip, agex::SynthObject::Wall), 0.02) << where;
      EXPECT_LT ((l.tip - l.base).norm (), 0.35f) << where;
      EXPECT_GT ((l.tip - l.base).norm (), 0.08f) << where;
      // Pixels are the projections with the dataset intrinsics.
      EXPECT_NEAR (l.tip_px.x (), k.fx * l.tip.x () / l.tip.z () + k.cx, 1e-2) << where;
      EXPECT_NEAR (l.tip_px.y (), k.fy * l.tip.y () / l.tip.z () + k.cy, 1e-2) << where;
      EXPECT_NEAR (l.base_px.x (), k.fx * l.base.x () / l.base.z () + k.cx, 1e-2) << where;
      EXPECT_LE (check.tolerance, l.part == agex::BodyPart::Head ? 0.15 : 0.08) << where;
      if (!l.visible)
        continue;
      ++visible;
      const long u = std::lround (l.tip_px.x ()), v = std::lround (l.tip_px.y ());
      ASSERT_TRUE (u >= 0 && v >= 0 && u < sensor.width && v < sensor.height) << where;
      // A valid depth near the tip pixel close to the tip's depth, seeing the tip's own part.
      double best = std::numeric_limits<double>::infinity ();
      for (long vv = std::max (0L, v - win); vv <= std::min<long> (sensor.height - 1, v + win); ++vv)
        for (long uu = std::max (0L, u - win); uu <= std::min<long> (sensor.width - 1, u + win); ++uu)
        {
          const std::size_t i = static_cast<std::size_t> (vv) * sensor.width + uu;
          const pcl::PointXYZ &p = frame.cloud.points[i];
          const bool own = std::find (check.primitives.begin (), check.primitives.end (), frame.primitive[i]) !=
                           check.primitives.end ();
          if (isFinite (p) && own && frame.object[i] == agex::SynthObject::Person)
            best = std::min (best, static_cast<double> (std::abs (p.z - l.tip.z ())));
        }
      EXPECT_LT (best, check.tolerance) << where;
    }
  }
  // Most tips are seen (some leave the frame or hide behind the body).
  EXPECT_GT (visible, labels / 2) << visible << " of " << labels << " visible";
}

TEST_P (SynthSensors, RendersAPersonInARoom)
{
  AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_131_01.bvh"));
  AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_02_01.bvh"));
  AGEX_REQUIRE_BODY ();
  const agex::SynthGenerator &gen = generator (sensorKind (), mesh ());
  std::set<std::string> sequences;
  for (int f = 0; f < 6; ++f)
  {
    const agex::SynthFrame frame = gen.render (static_cast<std::uint64_t> (f));
    sequences.insert (frame.sequence);
    std::size_t person = 0, floor = 0, valid = 0;
    for (std::size_t i = 0; i < frame.object.size (); ++i)
    {
      person += frame.object[i] == agex::SynthObject::Person;
      floor += frame.object[i] == agex::SynthObject::Floor;
      valid += isFinite (frame.cloud.points[i]);
    }
    EXPECT_GT (person, frame.object.size () / 50) << "frame " << f;
    EXPECT_GT (floor, 0u) << "frame " << f;
    // The bonn model keeps 255 depth steps (4.08 m), so far walls drop out as in the real frames.
    EXPECT_GT (valid, frame.object.size () / (sensorKind () == agex::SynthSensor::Bonn ? 8 : 4)) << "frame " << f;
    // Organized, camera frame: x = (u - cx) z / fx.
    const agex::CameraIntrinsics &k = gen.sensor ().intrinsics;
    for (int v = 0; v < gen.sensor ().height; v += 7)
      for (int u = 0; u < gen.sensor ().width; u += 7)
      {
        const pcl::PointXYZ &p = frame.cloud (u, v);
        if (!isFinite (p))
          continue;
        // The bonn view keeps each point of its nearest kinect pixel: up to half a
        // kinect pixel off the view pixel's own ray.
        const double off = sensorKind () == agex::SynthSensor::Bonn ? 0.55 * p.z / 525.0 : 1e-4;
        EXPECT_NEAR (p.x, (u - k.cx) * p.z / k.fx, off);
        EXPECT_NEAR (p.y, (v - k.cy) * p.z / k.fy, off);
        EXPECT_GT (p.z, 0.09f);
      }
  }
  EXPECT_EQ (sequences.size (), 2u) << "frames come from both clips";
}

INSTANTIATE_TEST_SUITE_P (Synth, SynthSensors,
                          ::testing::Combine (::testing::Values (agex::SynthSensor::Sr4000, agex::SynthSensor::Kinect,
                                                                 agex::SynthSensor::Bonn),
                                              ::testing::Bool ()),
                          [] (const ::testing::TestParamInfo<std::tuple<agex::SynthSensor, bool>> &info) {
                            return std::string (agex::synthSensorName (std::get<0> (info.param))) +
                                   (std::get<1> (info.param) ? "_mesh" : "_capsules");
                          });

TEST (SynthBonn, EightBitDepthStepsInThePortraitView)
{
  AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_131_01.bvh"));
  AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_02_01.bvh"));
  const agex::SynthGenerator &gen = generator (agex::SynthSensor::Bonn);
  // The view and intrinsics agex_convert bonn writes for the real frames.
  const agex::SensorModel &sensor = gen.sensor ();
  EXPECT_EQ (sensor.width, 144);
  EXPECT_EQ (sensor.height, 176);
  EXPECT_DOUBLE_EQ (sensor.intrinsics.fx, 210.0);
  EXPECT_DOUBLE_EQ (sensor.intrinsics.cx, 71.5);
  EXPECT_DOUBLE_EQ (sensor.intrinsics.cy, 87.5);
  EXPECT_EQ (gen.datasetInfo ().sensor, "bonn");
  std::size_t valid = 0;
  std::set<long> levels;
  for (int f = 0; f < 3; ++f)
  {
    const agex::SynthFrame frame = gen.render (static_cast<std::uint64_t> (f));
    ASSERT_EQ (frame.cloud.width, 144u);
    ASSERT_EQ (frame.cloud.height, 176u);
    ASSERT_EQ (frame.object.size (), frame.cloud.size ());
    for (const auto &p : frame.cloud.points)
    {
      if (!isFinite (p))
        continue;
      ++valid;
      const double level = p.z / agex::kBonnDepthStep;
      ASSERT_NEAR (level, std::round (level), 1e-3) << p.z;
      ASSERT_GE (level, 0.5);
      ASSERT_LE (level, 255.5);
      levels.insert (std::lround (level));
    }
  }
  EXPECT_GT (valid, 3u * 144 * 176 / 4);
  EXPECT_GT (levels.size (), 40u) << "a room's worth of depths";
}

TEST (SynthSr4000, MixedPixelsAtSilhouettesAndNoiseGrowingWithDepth)
{
  AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_131_01.bvh"));
  AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_02_01.bvh"));
  const agex::SynthGenerator &gen = generator (agex::SynthSensor::Sr4000);
  EXPECT_EQ (gen.sensor ().width, 144);
  EXPECT_EQ (gen.sensor ().height, 176);
  std::size_t mixed = 0, between_neighbours = 0;
  double near_sum2 = 0, far_sum2 = 0;
  std::size_t near_n = 0, far_n = 0;
  for (int f = 0; f < 6; ++f)
  {
    const agex::SynthFrame frame = gen.render (static_cast<std::uint64_t> (f));
    const int w = gen.sensor ().width, h = gen.sensor ().height;
    for (int v = 1; v + 1 < h; ++v)
      for (int u = 1; u + 1 < w; ++u)
      {
        const std::size_t i = static_cast<std::size_t> (v) * w + u;
        const float z = frame.cloud.points[i].z;
        if (!std::isfinite (z))
          continue;
        const float lo = frame.sample_min_z[i], hi = frame.sample_max_z[i];
        // A silhouette pixel (its samples see near and far) measured between them.
        if (hi - lo > 0.3f && z > lo + 0.05f && z < hi - 0.05f)
          ++mixed;
        // The same from the data alone: a pixel 15 cm behind one neighbour and in front of another.
        bool front = false, back = false;
        for (int dv = -1; dv <= 1; ++dv)
          for (int du = -1; du <= 1; ++du)
          {
            const float zn = frame.cloud (u + du, v + dv).z;
            front = front || zn < z - 0.15f;
            back = back || zn > z + 0.15f;
          }
        between_neighbours += front && back;
        // Noise on flat interior pixels, near and far.
        if (hi - lo < 0.005f && std::isfinite (frame.ideal_z[i]))
        {
          const double e = z - frame.ideal_z[i];
          if (frame.ideal_z[i] < 2.0f)
          {
            near_sum2 += e * e;
            ++near_n;
          }
          else if (frame.ideal_z[i] > 3.5f)
          {
            far_sum2 += e * e;
            ++far_n;
          }
        }
      }
  }
  EXPECT_GT (mixed, 50u);
  EXPECT_GT (between_neighbours, 20u);
  ASSERT_GT (near_n, 100u);
  ASSERT_GT (far_n, 100u);
  const double near_sigma = std::sqrt (near_sum2 / near_n), far_sigma = std::sqrt (far_sum2 / far_n);
  EXPECT_GT (near_sigma, 0.001);
  EXPECT_LT (near_sigma, 0.02);
  EXPECT_GT (far_sigma, 1.5 * near_sigma) << "noise grows with depth";
}

TEST (SynthKinect, VgaWithQuantisedDepthEdgeHolesAndNoMixedPixels)
{
  AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_131_01.bvh"));
  AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_02_01.bvh"));
  const agex::SynthGenerator &gen = generator (agex::SynthSensor::Kinect);
  const agex::SensorModel &s = gen.sensor ();
  EXPECT_EQ (s.width, 640);
  EXPECT_EQ (s.height, 480);
  EXPECT_EQ (s.intrinsics.fx, 525.0);
  EXPECT_EQ (s.intrinsics.fy, 525.0);
  EXPECT_EQ (s.intrinsics.cx, 319.5);
  EXPECT_EQ (s.intrinsics.cy, 239.5);
  const double fb8 = 8.0 * s.kinect_f_ir * s.kinect_baseline;
  std::size_t edge_pixels = 0, edge_holes = 0, inner_pixels = 0, inner_holes = 0, off = 0, unquantised = 0, valid = 0;
  for (int f = 0; f < 3; ++f)
  {
    const agex::SynthFrame frame = gen.render (static_cast<std::uint64_t> (f));
    const int w = s.width, h = s.height;
    // Distance (in pixels, up to 4) to a person / not-person boundary.
    auto nearBoundary = [&] (int u, int v, int r) {
      const bool here = frame.object[static_cast<std::size_t> (v) * w + u] == agex::SynthObject::Person;
      for (int dv = -r; dv <= r; ++dv)
        for (int du = -r; du <= r; ++du)
        {
          const int uu = std::clamp (u + du, 0, w - 1), vv = std::clamp (v + dv, 0, h - 1);
          if ((frame.object[static_cast<std::size_t> (vv) * w + uu] == agex::SynthObject::Person) != here)
            return true;
        }
      return false;
    };
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u)
      {
        const std::size_t i = static_cast<std::size_t> (v) * w + u;
        const float ideal = frame.ideal_z[i];
        const float z = frame.cloud.points[i].z;
        if (!std::isfinite (ideal) || ideal > 4.5f)
          continue;
        if (std::isfinite (z))
        {
          ++valid;
          // No mixed pixels: every depth is the surface's own, within the quantisation
          // and noise of its disparity.
          if (std::abs (z - ideal) > 0.05 + 0.01 * ideal * ideal)
            ++off;
          // Disparity quantisation: 8 f b / z is an integer.
          const double q = fb8 / z;
          if (std::abs (q - std::round (q)) > 1e-3)
            ++unquantised;
        }
        if (nearBoundary (u, v, 1))
        {
          ++edge_pixels;
          edge_holes += !std::isfinite (z);
        }
        else if (!nearBoundary (u, v, 4) && frame.object[i] == agex::SynthObject::Person)
        {
          ++inner_pixels;
          inner_holes += !std::isfinite (z);
        }
      }
  }
  ASSERT_GT (valid, 100000u);
  EXPECT_EQ (off, 0u) << "pixels far from their surface (mixed)";
  EXPECT_EQ (unquantised, 0u);
  ASSERT_GT (edge_pixels, 500u);
  ASSERT_GT (inner_pixels, 5000u);
  // Edge holes as fitted on real frames (doc/sensors.md: 4% of the band inside the outline),
  // plus projector shadows beside the person.
  EXPECT_GT (static_cast<double> (edge_holes) / edge_pixels, 0.05) << "holes along depth edges";
  EXPECT_LT (static_cast<double> (inner_holes) / inner_pixels, 0.05) << "few holes inside the body";
}

// ---------------------------------------------------------------------------
// A hand-built human skeleton (bvh11 names, metres): rendering without the shared data

/** A standing person, arms down, facing +z; frame 1 raises the left arm sideways. */
std::string
humanBvh ()
{
  struct J
  {
    std::string name;
    double x, y, z;
    std::vector<J> children;
  };
  auto chain = [] (std::vector<std::tuple<std::string, double, double, double>> joints, double ex, double ey, double ez) {
    J end{"End Site", ex, ey, ez, {}};
    for (auto it = joints.rbegin (); it != joints.rend (); ++it)
      end = J{std::get<0> (*it), std::get<1> (*it), std::get<2> (*it), std::get<3> (*it), {end}};
    return end;
  };
  J root{"Hips", 0, 0.95, 0, {}};
  for (const double s : {1.0, -1.0})
  {
    const std::string side = s > 0 ? "Left" : "Right";
    root.children.push_back (chain ({{side + "Hip", 0.09 * s, -0.08, 0}, {side + "Knee", 0, -0.42, 0},
                                     {side + "Ankle", 0, -0.4, 0}, {side + "Toe", 0, -0.04, 0.12}},
                                    0, 0, 0.06));
  }
  J spine = chain ({{"lowerback", 0, 0, 0}, {"Chest", 0, 0.12, 0}, {"Chest2", 0, 0.12, 0}, {"lowerneck", 0, 0.1, 0},
                    {"Neck", 0, 0.08, 0}, {"Head", 0, 0.08, 0}},
                   0, 0.1, 0);
  J *chest2 = &spine.children[0].children[0];
  for (const double s : {1.0, -1.0})
  {
    const std::string side = s > 0 ? "Left" : "Right";
    chest2->children.push_back (chain ({{side + "Shoulder", 0.18 * s, 0.08, 0}, {side + "Elbow", 0, -0.28, 0},
                                        {side + "Wrist", 0, -0.25, 0}},
                                       0, -0.08, 0));
  }
  root.children.push_back (spine);

  std::ostringstream out;
  int channels = 0, left_shoulder = -1;
  std::function<void (const J &, int, bool)> write = [&] (const J &j, int depth, bool is_root) {
    const std::string tab (static_cast<std::size_t> (depth), '\t');
    if (j.name == "End Site")
      out << tab << "End Site\n";
    else
      out << tab << (is_root ? "ROOT " : "JOINT ") << j.name << "\n";
    out << tab << "{\n" << tab << "\tOFFSET " << j.x << " " << j.y << " " << j.z << "\n";
    if (j.name != "End Site")
    {
      if (j.name == "LeftShoulder")
        left_shoulder = channels;
      out << tab << "\tCHANNELS " << (is_root ? "6 Xposition Yposition Zposition " : "3 ")
          << "Zrotation Yrotation Xrotation\n";
      channels += is_root ? 6 : 3;
    }
    for (const auto &c : j.children)
      write (c, depth + 1, false);
    out << tab << "}\n";
  };
  out << "HIERARCHY\n";
  write (root, 0, true);
  out << "MOTION\nFrames: 2\nFrame Time: 0.0083333\n";
  for (int f = 0; f < 2; ++f)
  {
    for (int c = 0; c < channels; ++c)
      out << (c ? " " : "") << (c == 1 ? 0.95 : (f == 1 && c == left_shoulder) ? 150.0 : 0.0);
    out << "\n";
  }
  return out.str ();
}

TEST (SynthRender, HandBuiltSkeletonWithoutTheSharedData)
{
  QuietPcl quiet;
  TempDir dir;
  writeAll (dir.file ("person.bvh"), humanBvh ());
  const agex::MotionClip clip = agex::MotionClip::load (dir.file ("person.bvh"));
  EXPECT_EQ (clip.scale, 1.0);
  EXPECT_EQ (clip.sequence, "person");
  EXPECT_NEAR (agex::restStandingHeight (clip), 1.72, 0.08);
  // Frame 1 raises the left hand above the shoulder.
  const agex::BodyModel rest = agex::buildBody (clip, 0, agex::BodyParams ()),
                        raised = agex::buildBody (clip, 1, agex::BodyParams ());
  EXPECT_LT (rest.tip[1].y (), 0.9);
  EXPECT_GT (raised.tip[1].y (), 1.5);
  EXPECT_NEAR (raised.tip[2].y (), rest.tip[2].y (), 1e-9) << "the right hand stays";

  for (const agex::SynthSensor sensor : {agex::SynthSensor::Sr4000, agex::SynthSensor::Kinect})
  {
    agex::SynthOptions options;
    options.motion_files = {dir.file ("person.bvh")};
    options.sensor = sensor;
    options.seed = 3;
    options.min_distance = 2.6;  // the whole person in the frame
    options.max_distance = 3.2;
    const agex::SynthGenerator gen (options);
    int visible_heads = 0;
    for (int f = 0; f < 3; ++f)
    {
      const agex::SynthFrame a = gen.render (static_cast<std::uint64_t> (f)), b = gen.render (static_cast<std::uint64_t> (f));
      ASSERT_EQ (a.cloud.size (), b.cloud.size ());
      for (std::size_t i = 0; i < a.cloud.size (); ++i)
        ASSERT_EQ (bits (a.cloud.points[i].z), bits (b.cloud.points[i].z)) << "render is not deterministic";
      std::size_t person = 0;
      for (const auto o : a.object)
        person += o == agex::SynthObject::Person;
      EXPECT_GT (person, a.object.size () / 40);
      visible_heads += a.labels[0].visible;
      for (std::size_t j = 0; j < a.labels.size (); ++j)
        if (a.labels[j].visible)
        {
          const long u = std::lround (a.labels[j].tip_px.x ()), v = std::lround (a.labels[j].tip_px.y ());
          EXPECT_TRUE (u >= 0 && v >= 0 && u < gen.sensor ().width && v < gen.sensor ().height);
        }
    }
    EXPECT_GE (visible_heads, 2) << agex::synthSensorName (sensor);
  }
}

TEST (SynthColour, BodyPartsAreDressedAndTheDepthStaysTheSame)
{
  QuietPcl quiet;
  TempDir dir;
  writeAll (dir.file ("person.bvh"), humanBvh ());
  const agex::MotionClip clip = agex::MotionClip::load (dir.file ("person.bvh"));
  const agex::BodyModel body = agex::buildBody (clip, 0, agex::BodyParams ());
  auto materialOf = [&] (int tip) { return body.primitives[static_cast<std::size_t> (body.tip_primitives[tip][0])].material; };
  EXPECT_EQ (materialOf (0), agex::SynthMaterial::Skin) << "head";
  EXPECT_EQ (materialOf (1), agex::SynthMaterial::Skin) << "hand";
  EXPECT_EQ (materialOf (3), agex::SynthMaterial::Shoes) << "foot";
  std::set<agex::SynthMaterial> used;
  for (const auto &p : body.primitives)
    used.insert (p.material);
  EXPECT_EQ (used, (std::set<agex::SynthMaterial>{agex::SynthMaterial::Skin, agex::SynthMaterial::Top,
                                                   agex::SynthMaterial::Bottom, agex::SynthMaterial::Shoes}));

  agex::SynthOptions options;
  options.motion_files = {dir.file ("person.bvh")};
  options.sensor = agex::SynthSensor::Kinect;
  options.seed = 3;
  options.min_distance = 2.6;
  options.max_distance = 3.2;
  const agex::SynthGenerator depth_only (options);
  options.colour = true;
  const agex::SynthGenerator coloured (options);
  std::vector<std::array<double, 3>> skin_means;
  for (std::uint64_t f = 0; f < 3; ++f)
  {
    const agex::SynthFrame d = depth_only.render (f), c = coloured.render (f), again = coloured.render (f);
    EXPECT_TRUE (d.colour.empty ());
    ASSERT_EQ (c.colour.size (), c.cloud.size ());
    for (std::size_t i = 0; i < c.cloud.size (); ++i)
      ASSERT_EQ (bits (d.cloud.points[i].z), bits (c.cloud.points[i].z)) << "colour changed the depth at " << i;
    EXPECT_TRUE (c.colour == again.colour) << "colour is not deterministic";

    // Away from outlines, a surface's colour is its albedo times a brightness: bright
    // pixels of one material share their chromaticity (mean absolute deviation about
    // 0.01, above 0.1 for unrelated colours).
    const int w = coloured.sensor ().width, h = coloured.sensor ().height;
    std::map<agex::SynthMaterial, std::vector<std::array<double, 3>>> chroma;
    for (int v = 2; v < h - 2; ++v)
      for (int u = 2; u < w - 2; ++u)
      {
        const std::size_t i = static_cast<std::size_t> (v) * w + u;
        const int prim = c.primitive[i];
        if (prim < 0 || c.scene.primitives[static_cast<std::size_t> (prim)].object != agex::SynthObject::Person)
          continue;
        bool interior = true;
        for (int dv = -2; dv <= 2 && interior; ++dv)
          for (int du = -2; du <= 2; ++du)
            interior = interior && c.primitive[i + static_cast<std::size_t> (dv * w + du)] == prim;
        const auto &rgb = c.colour[i];
        const double sum = rgb[0] + rgb[1] + rgb[2];
        if (!interior || sum < 150.0 || std::max ({rgb[0], rgb[1], rgb[2]}) > 250)
          continue;
        chroma[c.scene.primitives[static_cast<std::size_t> (prim)].material].push_back (
            {rgb[0] / sum, rgb[1] / sum, rgb[2] / sum});
      }
    ASSERT_FALSE (chroma[agex::SynthMaterial::Skin].empty ()) << "frame " << f << ": no skin seen";
    for (const auto &[material, values] : chroma)
    {
      if (values.size () < 20)
        continue;
      std::array<double, 3> mean{0, 0, 0};
      for (const auto &x : values)
        for (int k = 0; k < 3; ++k)
          mean[k] += x[k] / values.size ();
      double spread = 0.0;  // mean absolute deviation
      for (const auto &x : values)
        for (int k = 0; k < 3; ++k)
          spread += std::abs (x[k] - mean[k]) / (3.0 * values.size ());
      EXPECT_LT (spread, 0.05) << "frame " << f << ", material " << static_cast<int> (material);
      if (material == agex::SynthMaterial::Skin)
        skin_means.push_back (mean);
    }
  }
  ASSERT_EQ (skin_means.size (), 3u);
  EXPECT_TRUE (skin_means[0] != skin_means[1] || skin_means[1] != skin_means[2]) << "every frame has the same look";

  // Colour datasets hold XYZRGBA frames whose depth reads back like a depth-only one's.
  agex::writeSyntheticDataset (coloured, 2, dir.file ("c"), false);
  options.colour = false;
  agex::writeSyntheticDataset (depth_only, 2, dir.file ("d"), false);
  const agex::Dataset c = agex::Dataset::read (dir.file ("c")), d = agex::Dataset::read (dir.file ("d"));
  for (const auto &frame : c.frames ())
  {
    const pcl::PCLPointCloud2 raw = agex::readPcd (c.framePath (frame.id));
    bool has_rgba = false;
    for (const auto &field : raw.fields)
      has_rgba = has_rgba || field.name == "rgba";
    EXPECT_TRUE (has_rgba) << frame.id;
    const auto a = c.loadFrame (frame.id), b = d.loadFrame (frame.id);
    ASSERT_EQ (a->size (), b->size ());
    for (std::size_t i = 0; i < a->size (); ++i)
      ASSERT_EQ (bits ((*a)[i].z), bits ((*b)[i].z));
  }
  EXPECT_EQ (readAll (dir.file ("c/labels.csv")), readAll (dir.file ("d/labels.csv")));

  // The Bonn view is grey depth: colour is refused.
  options.colour = true;
  options.sensor = agex::SynthSensor::Bonn;
  EXPECT_THROW (agex::SynthGenerator{options}, std::invalid_argument);
}

// ---------------------------------------------------------------------------
// Datasets

std::map<std::string, std::string>
filesOf (const fs::path &root)
{
  std::map<std::string, std::string> files;
  for (const auto &entry : fs::recursive_directory_iterator (root))
    if (entry.is_regular_file ())
      files[fs::relative (entry.path (), root).string ()] = readAll (entry.path ().string ());
  return files;
}

TEST (SynthDataset, SameSeedSameBytesDifferentSeedDifferent)
{
  AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_131_01.bvh"));
  AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_02_01.bvh"));
  QuietPcl quiet;
  TempDir dir;
  auto run = [&] (std::uint64_t seed, const std::string &name, bool overwrite = false) {
    agex::SynthOptions options;
    options.motion_files = {sharedData ("mocap/cmu_131_01.bvh"), sharedData ("mocap/cmu_02_01.bvh")};
    options.seed = seed;
    const agex::SynthGenerator gen (options);
    int calls = 0;
    const agex::SynthRunStats stats =
        agex::writeSyntheticDataset (gen, 4, dir.file (name), overwrite, [&] (int done, int total) {
          EXPECT_EQ (done, ++calls);
          EXPECT_EQ (total, 4);
        });
    EXPECT_EQ (stats.frames, 4);
    EXPECT_EQ (stats.labels, 20);
    return filesOf (dir.path () / name);
  };
  const auto a = run (5, "a"), b = run (5, "b"), c = run (6, "c");
  ASSERT_EQ (a.size (), 14u);  // dataset.json, labels.csv, 4 frames, 4 part-label and 4 person images
  EXPECT_TRUE (a == b) << "the same seed wrote different bytes";
  EXPECT_NE (a.at ("labels.csv"), c.at ("labels.csv"));
  EXPECT_NE (a.at ("frames/000000.pcd"), c.at ("frames/000000.pcd"));

  // The dataset reads back: sensor, intrinsics, sequences, labels.
  const agex::Dataset ds = agex::Dataset::read (dir.file ("a"));
  EXPECT_EQ (ds.info ().sensor, "sr4000");
  EXPECT_EQ (ds.info ().width, 144);
  EXPECT_EQ (ds.info ().height, 176);
  EXPECT_EQ (ds.info ().intrinsics.fx, 220.0);
  EXPECT_NE (ds.info ().provenance.find ("cmu_02_01.bvh"), std::string::npos);
  EXPECT_NE (ds.info ().provenance.find ("seed 5"), std::string::npos);
  EXPECT_NE (ds.info ().provenance.find ("girth="), std::string::npos);
  ASSERT_EQ (ds.frames ().size (), 4u);
  EXPECT_EQ (ds.frames ()[0].id, "000000");
  for (const auto &frame : ds.frames ())
  {
    EXPECT_TRUE (frame.sequence == "cmu_131_01" || frame.sequence == "cmu_02_01") << frame.sequence;
    EXPECT_EQ (ds.labelsOf (frame.id).size (), 5u);
    EXPECT_TRUE (ds.isKeyframe (frame.id));
    const auto cloud = ds.loadFrame (frame.id);
    EXPECT_EQ (cloud->width, 144u);
  }

  // An existing output is refused without overwrite and replaced with it.
  try
  {
    run (5, "a");
    ADD_FAILURE () << "an existing dataset was overwritten";
  }
  catch (const agex::DatasetError &e)
  {
    EXPECT_NE (std::string (e.what ()).find ("already exists"), std::string::npos) << e.what ();
  }
  EXPECT_TRUE (run (5, "a", true) == b);
}
// ---------------------------------------------------------------------------
// Triangle meshes and the MakeHuman body

/** Nearest hit over every triangle, without the hierarchy. */
double
bruteForceHit (const agex::SynthMesh &mesh, const Eigen::Vector3d &o, const Eigen::Vector3d &d)
{
  double best = -1.0;
  for (const auto &t : mesh.triangles ())
  {
    const Eigen::Vector3d &a = mesh.vertices ()[t[0]];
    const Eigen::Vector3d e1 = mesh.vertices ()[t[1]] - a, e2 = mesh.vertices ()[t[2]] - a;
    Eigen::Matrix3d m;
    m << -d, e1, e2;
    if (std::abs (m.determinant ()) < 1e-15)
      continue;
    const Eigen::Vector3d x = m.colPivHouseholderQr ().solve (o - a);  // (t, u, v)
    if (x[0] > 1e-9 && x[1] >= 0 && x[2] >= 0 && x[1] + x[2] <= 1 && (best < 0 || x[0] < best))
      best = x[0];
  }
  return best;
}

/** A UV sphere of radius r around c. */
agex::SynthMesh
sphereMesh (const Eigen::Vector3d &c, double r, int rings, int segments)
{
  std::vector<Eigen::Vector3d> v;
  std::vector<Eigen::Vector3i> t;
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < segments; ++j)
    {
      const double theta = M_PI * i / rings, phi = 2 * M_PI * j / segments;
      v.push_back (c + r * Eigen::Vector3d (std::sin (theta) * std::cos (phi), std::cos (theta), std::sin (theta) * std::sin (phi)));
    }
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j)
    {
      const int a = i * segments + j, b = i * segments + (j + 1) % segments;
      t.emplace_back (a, b, a + segments);
      t.emplace_back (b, b + segments, a + segments);
    }
  return agex::SynthMesh (v, t);
}

TEST (SynthMesh, OneTriangleHitNormalAndDistance)
{
  const agex::SynthMesh tri ({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
  Eigen::Vector3d n;
  EXPECT_NEAR (tri.intersect ({0.2, 0.2, 1.0}, {0, 0, -1}, 0.0, &n), 1.0, 1e-12);
  EXPECT_NEAR (n.z (), 1.0, 1e-12) << "the normal faces the ray";
  EXPECT_NEAR (tri.intersect ({0.2, 0.2, -2.0}, {0, 0, 1}, 0.0, &n), 2.0, 1e-12);
  EXPECT_NEAR (n.z (), -1.0, 1e-12);
  EXPECT_LT (tri.intersect ({0.8, 0.8, 1.0}, {0, 0, -1}, 0.0, &n), 0.0) << "outside the triangle";
  EXPECT_LT (tri.intersect ({0.2, 0.2, 1.0}, {0, 0, 1}, 0.0, &n), 0.0) << "behind the ray";
  EXPECT_LT (tri.intersect ({0.2, 0.2, 1.0}, {0, 0, -1}, 1.5, &n), 0.0) << "before t_min";
  EXPECT_NEAR (tri.distance ({0.2, 0.2, 0.3}), 0.3, 1e-12);
  EXPECT_NEAR (tri.distance ({2, 0, 0}), 1.0, 1e-12);
  EXPECT_NEAR (tri.distance ({-1, -1, 0}), std::sqrt (2.0), 1e-12);
  EXPECT_NEAR (tri.distance ({1, 1, 0}), std::sqrt (0.5), 1e-12);
  EXPECT_THROW (agex::SynthMesh ({{0, 0, 0}}, {{0, 1, 2}}), std::invalid_argument);
  const agex::SynthMesh empty ({}, {});
  EXPECT_LT (empty.intersect ({0, 0, 0}, {0, 0, 1}, 0.0, nullptr), 0.0);
}

TEST (SynthMesh, HierarchyFindsTheSameHitsAsEveryTriangle)
{
  const Eigen::Vector3d c (0.1, -0.2, 3.0);
  const agex::SynthMesh sphere = sphereMesh (c, 0.5, 24, 40);
  ASSERT_GT (sphere.triangles ().size (), 1000u);
  agex::SynthRng rng (3);
  int hits = 0;
  for (int i = 0; i < 400; ++i)
  {
    const Eigen::Vector3d o (rng.uniform (-0.3, 0.3), rng.uniform (-0.3, 0.3), 0.0);
    const Eigen::Vector3d aim = c + Eigen::Vector3d (rng.uniform (-0.6, 0.6), rng.uniform (-0.6, 0.6), 0.0);
    const Eigen::Vector3d d = (aim - o).normalized ();
    Eigen::Vector3d n;
    const double t = sphere.intersect (o, d, 0.0, &n), expected = bruteForceHit (sphere, o, d);
    ASSERT_EQ (t < 0, expected < 0) << "ray " << i;
    if (t < 0)
      continue;
    ++hits;
    EXPECT_NEAR (t, expected, 1e-9) << "ray " << i;
    const Eigen::Vector3d p = o + t * d;
    EXPECT_NEAR ((p - c).norm (), 0.5, 0.01) << "on the sphere, up to the tessellation";
    EXPECT_LT (n.dot (d), 0.0) << "the normal faces the ray";
    EXPECT_LT (sphere.distance (p), 1e-9);
    EXPECT_NEAR (sphere.distance (c + (p - c).normalized ()), 0.5, 0.01);
  }
  EXPECT_GT (hits, 100);
  // Rays from anywhere, inside the sphere too, in any direction, some exactly along an
  // axis (the slab test's 0 * inf case), some with t_min > 0.
  const agex::SynthMesh box ({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}},
                             {{0, 1, 2}, {0, 2, 3}, {4, 6, 5}, {4, 7, 6}, {0, 4, 5}, {0, 5, 1},
                              {3, 2, 6}, {3, 6, 7}, {0, 3, 7}, {0, 7, 4}, {1, 5, 6}, {1, 6, 2}});
  for (int i = 0; i < 600; ++i)
  {
    const agex::SynthMesh &mesh = i % 2 ? sphere : box;
    const Eigen::Vector3d centre = i % 2 ? c : Eigen::Vector3d (0.5, 0.5, 0.5);
    const Eigen::Vector3d o = centre + Eigen::Vector3d (rng.uniform (-1, 1), rng.uniform (-1, 1), rng.uniform (-1, 1));
    Eigen::Vector3d d (rng.normal (), rng.normal (), rng.normal ());
    if (i % 5 == 0)
      d = Eigen::Vector3d::Unit (i % 3) * (rng.chance (0.5) ? 1.0 : -1.0);
    d.normalize ();
    const double t_min = i % 3 == 0 ? rng.uniform (0.0, 0.5) : 0.0;
    const double t = mesh.intersect (o, d, t_min, nullptr);
    // The brute force counts hits after 1e-9; shift the origin to start at t_min.
    double expected = bruteForceHit (mesh, o + t_min * d, d);
    if (expected >= 0)
      expected += t_min;
    ASSERT_EQ (t < 0, expected < 0) << "ray " << i << " t " << t << " expected " << expected;
    if (t >= 0)
    {
      EXPECT_NEAR (t, expected, 1e-9) << "ray " << i;
    }
  }
  // Placed in a scene as a primitive: the same hits after a rigid transform.
  Eigen::Isometry3d move = Eigen::Isometry3d::Identity ();
  move.rotate (Eigen::AngleAxisd (0.7, Eigen::Vector3d (1, 2, 3).normalized ()));
  move.pretranslate (Eigen::Vector3d (0.4, -1.0, 2.0));
  const agex::SynthPrimitive here = agex::SynthPrimitive::triangleMesh (
      std::make_shared<const agex::SynthMesh> (sphere), agex::SynthObject::Person);
  const agex::SynthPrimitive there = here.transformed (move);
  const Eigen::Vector3d o (0, 0, 0), d = (c - Eigen::Vector3d (0.1, 0.05, 0.0)).normalized ();
  Eigen::Vector3d n_here, n_there;
  const double t_here = here.intersect (o, d, 0.0, &n_here);
  ASSERT_GT (t_here, 0.0);
  EXPECT_NEAR (there.intersect (move * o, move.linear () * d, 0.0, &n_there), t_here, 1e-9);
  EXPECT_LT ((n_there - move.linear () * n_here).norm (), 1e-9);
  Eigen::Vector3d centre_here, centre_there;
  double r_here, r_there;
  ASSERT_TRUE (here.boundingSphere (centre_here, r_here));
  ASSERT_TRUE (there.boundingSphere (centre_there, r_there));
  EXPECT_LT ((centre_there - move * centre_here).norm (), 1e-9);
  EXPECT_NEAR (there.distance (move * (c + Eigen::Vector3d (0, 0, -1))), 0.5, 0.01);
}

TEST (HumanMesh, LoadsTheMakeHumanBody)
{
  AGEX_REQUIRE_MAKEHUMAN ();
  const agex::HumanMesh mesh = agex::HumanMesh::load (sharedData ("makehuman"));
  EXPECT_EQ (mesh.vertices ().size (), 13380u);   // group body of base.obj
  EXPECT_EQ (mesh.triangles ().size (), 2 * 13378u);  // its quads, split
  EXPECT_EQ (mesh.bones ().size (), 163u);
  EXPECT_NEAR (mesh.height (), 1.67, 0.05);
  for (std::size_t b = 0; b < mesh.bones ().size (); ++b)
    EXPECT_LT (mesh.bones ()[b].parent, static_cast<int> (b)) << "parents come first";
  std::vector<int> per_part (agex::HumanMesh::kParts, 0);
  for (std::size_t v = 0; v < mesh.vertices ().size (); ++v)
  {
    double sum = 0;
    for (const auto &i : mesh.influences ()[v])
      sum += i.weight;
    ASSERT_NEAR (sum, 1.0, 1e-9) << "vertex " << v;
    ++per_part[mesh.parts ()[v]];
  }
  for (int p = 0; p < agex::HumanMesh::kParts; ++p)
    EXPECT_GT (per_part[p], 200) << "part " << p;
  EXPECT_EQ (per_part[agex::HumanMesh::LeftHand], per_part[agex::HumanMesh::RightHand]) << "symmetric weights";
  // Tips: the head's is the highest point of the body; hands on their own side (+X is
  // the body's left), below the shoulders in MakeHuman's A pose; toes in front.
  const auto &tips = mesh.tipVertices ();
  double top = -1e9;
  for (const auto &v : mesh.vertices ())
    top = std::max (top, v.y ());
  EXPECT_NEAR (mesh.vertices ()[tips[agex::HumanMesh::Head]].y (), top, 0.01);
  const Eigen::Vector3d left_hand = mesh.vertices ()[tips[agex::HumanMesh::LeftHand]],
                        right_hand = mesh.vertices ()[tips[agex::HumanMesh::RightHand]];
  EXPECT_GT (left_hand.x (), 0.4);
  EXPECT_NEAR (right_hand.x (), -left_hand.x (), 1e-6);
  EXPECT_LT (left_hand.y (), 0.3);
  for (const auto part : {agex::HumanMesh::LeftFoot, agex::HumanMesh::RightFoot})
  {
    const Eigen::Vector3d toe = mesh.vertices ()[tips[part]];
    EXPECT_GT (toe.z (), 0.15);
    EXPECT_LT (toe.y (), -0.7);
  }
}

TEST (HumanMesh, BadFilesNameTheFile)
{
  TempDir dir;
  auto write = [&] (const std::string &name, const std::string &text) { std::ofstream (dir.file (name)) << text; };
  auto error = [&] () -> std::string {
    try
    {
      agex::HumanMesh::load (dir.path ().string ());
    }
    catch (const agex::HumanMeshError &e)
    {
      return e.what ();
    }
    return "(no error)";
  };
  EXPECT_NE (error ().find ("base.obj: cannot open"), std::string::npos) << error ();
  write ("base.obj", "v 0 0 0\nv 1 0 0\ng body\nf 1 2 7\n");
  EXPECT_NE (error ().find ("base.obj:4: face corner 7 names no vertex"), std::string::npos) << error ();
  write ("base.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\ng helper-tights\nf 1 2 3\n");
  EXPECT_NE (error ().find ("no faces in group 'body'"), std::string::npos) << error ();
  write ("base.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\ng body\nf 1/1 2/2 3/3\n");
  EXPECT_NE (error ().find ("default.mhskel: cannot open"), std::string::npos) << error ();
  write ("default.mhskel", "{\"bones\": {");
  write ("default_weights.mhw", "{\"weights\": {}}");
  EXPECT_NE (error ().find ("default.mhskel: not valid JSON"), std::string::npos) << error ();
  write ("default.mhskel",
         "{\"joints\": {\"a\": [0], \"b\": [9]}, \"bones\": {\"root\": {\"head\": \"a\", \"tail\": \"b\", \"parent\": null}}}");
  EXPECT_NE (error ().find ("joint 'b' names vertex 9"), std::string::npos) << error ();
  write ("default.mhskel",
         "{\"joints\": {\"a\": [0], \"b\": [1]}, \"bones\": {\"root\": {\"head\": \"a\", \"tail\": \"b\", \"parent\": \"x\"}}}");
  EXPECT_NE (error ().find ("bone 'root' has a parent that is missing"), std::string::npos) << error ();
  write ("default.mhskel",
         "{\"joints\": {\"a\": [0], \"b\": [1]}, \"bones\": {\"root\": {\"head\": \"a\", \"tail\": \"b\", \"parent\": null}}}");
  EXPECT_NE (error ().find ("default.mhskel: the skeleton has no bone 'head'"), std::string::npos) << error ();
  write ("default.mhskel",
         "{\"joints\": {\"a\": [0]}, \"bones\": {\"root\": {\"head\": \"a\", \"tail\": \"zz\", \"parent\": null}}}");
  EXPECT_NE (error ().find ("bone 'root' names joint 'zz'"), std::string::npos) << error ();
  write ("default.mhskel",
         "{\"joints\": {\"a\": [0], \"b\": [1e300]}, \"bones\": {\"root\": {\"head\": \"a\", \"tail\": \"b\", \"parent\": null}}}");
  EXPECT_NE (error ().find ("joint 'b' names vertex 1e+300"), std::string::npos) << error ();
  write ("default.mhskel", "[1, 2]");
  EXPECT_NE (error ().find ("default.mhskel: not a MakeHuman skeleton"), std::string::npos) << error ();
}

TEST (HumanMesh, BadWeightsNameTheFile)
{
  AGEX_REQUIRE_MAKEHUMAN ();
  TempDir dir;
  for (const char *name : {"base.obj", "default.mhskel"})
    fs::copy_file (sharedData (std::string ("makehuman/") + name), dir.path () / name);
  auto error = [&] (const std::string &weights) -> std::string {
    std::ofstream (dir.file ("default_weights.mhw")) << weights;
    try
    {
      agex::HumanMesh::load (dir.path ().string ());
    }
    catch (const agex::HumanMeshError &e)
    {
      return e.what ();
    }
    return "(no error)";
  };
  std::string e = error ("{\"weights\": {\"nobone\": [[0, 1.0]]}}");
  EXPECT_NE (e.find ("default_weights.mhw: weights for bone 'nobone'"), std::string::npos) << e;
  e = error ("{\"weights\": {\"head\": [[18446744073709551615, 1.0]]}}");
  EXPECT_NE (e.find ("default_weights.mhw: bone 'head': bad weight"), std::string::npos) << e;
  e = error ("{\"weights\": {\"head\": [[0, -1]]}}");
  EXPECT_NE (e.find ("bad weight"), std::string::npos) << e;
  e = error ("{\"weights\": {\"head\": [[0, 1.0]]}}");
  EXPECT_NE (e.find ("has no skin weight"), std::string::npos) << e;
  e = error ("{\"weights\": 3}");
  EXPECT_NE (e.find ("default_weights.mhw: not MakeHuman weights"), std::string::npos) << e;
}

TEST (HumanMesh, PosedBodyFollowsTheMotionCapture)
{
  AGEX_REQUIRE_MAKEHUMAN ();
  AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_05_06.bvh"));
  const agex::HumanMesh mesh = agex::HumanMesh::load (sharedData ("makehuman"));
  const agex::MotionClip clip = agex::MotionClip::load (sharedData ("mocap/cmu_05_06.bvh"));
  const agex::SkeletonMap &m = clip.map;
  agex::BodyParams params;
  const double height = agex::restStandingHeight (clip);
  auto angle = [] (const Eigen::Vector3d &a, const Eigen::Vector3d &b) {
    return std::acos (std::clamp (a.normalized ().dot (b.normalized ()), -1.0, 1.0)) * 180.0 / M_PI;
  };
  for (const int frame : {0, 150, 300, 450, 600, 750})
  {
    const agex::BodyModel body = agex::buildMeshBody (clip, frame, params, mesh);
    std::vector<Eigen::Isometry3d> g;
    clip.motion.pose (frame, clip.scale, g);
    auto P = [&] (int j) { return g[static_cast<std::size_t> (j)].translation (); };
    const std::string where = "frame " + std::to_string (frame);
    ASSERT_EQ (body.primitives.size (), static_cast<std::size_t> (agex::HumanMesh::kParts));
    EXPECT_NEAR (body.highest - body.lowest, height, 0.35 * height) << where;
    // Colour frames dress the parts: skin on head and hands, shoes, trousers, a top.
    EXPECT_EQ (body.primitives[agex::HumanMesh::Head].material, agex::SynthMaterial::Skin);
    EXPECT_EQ (body.primitives[agex::HumanMesh::RightHand].material, agex::SynthMaterial::Skin);
    EXPECT_EQ (body.primitives[agex::HumanMesh::LeftFoot].material, agex::SynthMaterial::Shoes);
    EXPECT_EQ (body.primitives[agex::HumanMesh::LeftLeg].material, agex::SynthMaterial::Bottom);
    EXPECT_EQ (body.primitives[agex::HumanMesh::Trunk].material, agex::SynthMaterial::Top);
    EXPECT_EQ (body.primitives[agex::HumanMesh::RightArm].material, agex::SynthMaterial::Top);
    // Every segment points where the skeleton's does.
    const std::vector<Eigen::Vector3d> heads = agex::meshBoneHeads (clip, frame, params, mesh);
    auto H = [&] (const std::string &bone) { return heads[static_cast<std::size_t> (mesh.bone (bone))]; };
    for (int side = 0; side < 2; ++side)
    {
      const std::string s = side == 0 ? ".L" : ".R", at = where + " side " + std::to_string (side);
      EXPECT_LT (angle (H ("lowerarm01" + s) - H ("upperarm01" + s), P (m.elbow[side]) - P (m.shoulder[side])), 1.0) << at;
      EXPECT_LT (angle (H ("wrist" + s) - H ("lowerarm01" + s), P (m.wrist[side]) - P (m.elbow[side])), 1.0) << at;
      EXPECT_LT (angle (H ("lowerleg01" + s) - H ("upperleg01" + s), P (m.knee[side]) - P (m.hip[side])), 1.0) << at;
      EXPECT_LT (angle (H ("foot" + s) - H ("lowerleg01" + s), P (m.ankle[side]) - P (m.knee[side])), 1.0) << at;
      EXPECT_EQ (H ("wrist" + s), body.base[1 + side]) << "the hand's base is the wrist";
      EXPECT_EQ (H ("foot" + s), body.base[3 + side]) << "the foot's base is the ankle";
      // The hand's tip lies beyond its wrist, away from the elbow.
      EXPECT_GT ((body.tip[1 + side] - body.base[1 + side]).dot (P (m.wrist[side]) - P (m.elbow[side])), 0.0) << at;
    }
    EXPECT_LT (angle (H ("head") - H ("neck01"), P (m.head) - P (m.neck)), 1.0) << where;
    // The root joint carries the hips: the mesh's hip centre is on it.
    EXPECT_LT ((0.5 * (H ("upperleg01.L") + H ("upperleg01.R")) - P (m.root)).norm (), 1e-9) << where;
    // Each tip lies on its own part's mesh.
    for (int i = 0; i < 5; ++i)
      EXPECT_LT (body.primitives[static_cast<std::size_t> (body.tip_primitives[i][0])].distance (body.tip[i]), 1e-9);
  }
}

TEST (HumanMesh, MeshFramesAreDeterministic)
{
  AGEX_REQUIRE_MAKEHUMAN ();
  AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_02_01.bvh"));
  auto render = [] (std::uint64_t seed) {
    agex::SynthOptions options;
    options.motion_files = {sharedData ("mocap/cmu_02_01.bvh")};
    options.body_mesh = sharedData ("makehuman");
    options.seed = seed;
    options.subjects = 2;
    const agex::SynthGenerator gen (options);
    EXPECT_NE (gen.datasetInfo ().provenance.find ("MakeHuman mesh bodies"), std::string::npos);
    return gen.render (3);
  };
  const agex::SynthFrame a = render (4), b = render (4), c = render (5);
  ASSERT_EQ (a.cloud.size (), b.cloud.size ());
  bool differs = false;
  for (std::size_t i = 0; i < a.cloud.size (); ++i)
  {
    const auto &p = a.cloud.points[i], &q = b.cloud.points[i], &r = c.cloud.points[i];
    ASSERT_EQ (std::memcmp (&p, &q, sizeof p), 0) << "pixel " << i;
    differs = differs || std::memcmp (&p, &r, sizeof p) != 0;
  }
  EXPECT_TRUE (differs);
  ASSERT_EQ (a.labels.size (), 5u);
  for (std::size_t j = 0; j < 5; ++j)
    EXPECT_EQ (a.labels[j].tip, b.labels[j].tip);
}
}  // namespace
