// Whole synthetic scenes (SynthLayout::Whole, agex_synth --layout whole): the camera's height,
// pitch and roll keep their ranges and spread over them, people cut by the frame's borders
// are labelled only where they are seen, close-range frames show one upper body and nothing
// else, background-removed frames keep only people, a smaller frame size renders the same
// scene with the intrinsics scaled, and bad settings are refused.

#include "test_support.h"

#include <agex/simulation/synthetic_scene.h>

#include <cmath>
#include <functional>

namespace
{
using namespace agex_test;

agex::SynthOptions
wholeOptions (agex::SynthSensor sensor = agex::SynthSensor::Kinect)
{
  agex::SynthOptions options;
  options.motion_files = {sharedData ("mocap/cmu_131_01.bvh"), sharedData ("mocap/cmu_02_01.bvh")};
  options.sensor = sensor;
  options.seed = 7;
  options.people = 4;
  options.layout = agex::SynthLayout::Whole;
  options.width = 320;  // faster; the scene is the same at any size
  options.height = 240;
  return options;
}

#define AGEX_REQUIRE_WHOLE_MOCAP()                                                                                   \
  do                                                                                                                \
  {                                                                                                                 \
    AGEX_REQUIRE_SHARED_FILE (sharedData ("mocap/cmu_131_01.bvh"), "the CMU motion capture (../shared/data/mocap)"); \
    AGEX_REQUIRE_SHARED_FILE (sharedData ("mocap/cmu_02_01.bvh"), "the CMU motion capture (../shared/data/mocap)");  \
  } while (0)

/** The camera's pitch (up positive) and height above the floor plan's y = 0. */
void
cameraPose (const agex::SynthFrame &frame, double &pitch_deg, double &height)
{
  const Eigen::Vector3d forward = frame.world_to_camera.linear ().row (2).transpose ();
  pitch_deg = std::asin (std::max (-1.0, std::min (1.0, forward.y ()))) * 180.0 / M_PI;
  height = frame.world_to_camera.inverse ().translation ().y ();
}

bool
anyOf (const agex::SynthFrame &frame, agex::SynthObject object)
{
  for (std::size_t i = 0; i < frame.object.size (); ++i)
    if (frame.object[i] == object && std::isfinite (frame.cloud[i].z))
      return true;
  return false;
}
}  // namespace

TEST (SynthWholeScenes, BadSettingsAreRefused)
{
  AGEX_REQUIRE_WHOLE_MOCAP ();
  auto refused = [] (const std::function<void (agex::SynthOptions &)> &change) {
    agex::SynthOptions o = wholeOptions ();
    change (o);
    EXPECT_THROW (agex::SynthGenerator {o}, std::invalid_argument);
  };
  refused ([] (agex::SynthOptions &o) { o.min_pitch_deg = -95; });
  refused ([] (agex::SynthOptions &o) { o.min_pitch_deg = 20; });  // above max_pitch_deg
  refused ([] (agex::SynthOptions &o) { o.max_roll_deg = -1; });
  refused ([] (agex::SynthOptions &o) { o.close_range_share = 1.5; });
  refused ([] (agex::SynthOptions &o) { o.background_removed_share = std::nan (""); });
  refused ([] (agex::SynthOptions &o) { o.border_share = 0.8; });
  refused ([] (agex::SynthOptions &o) { o.width = 320, o.height = 200; });  // not the sensor's aspect
  refused ([] (agex::SynthOptions &o) { o.width = 8, o.height = 6; });
  refused ([] (agex::SynthOptions &o) { o.sensor = agex::SynthSensor::Bonn; });  // 144x176 only
  refused ([] (agex::SynthOptions &o) { o.max_height = 50; });
  refused ([] (agex::SynthOptions &o) { o.kinect_window = 4; });   // even
  refused ([] (agex::SynthOptions &o) { o.kinect_window = 33; });
  agex::SynthLayout layout;
  EXPECT_FALSE (agex::parseSynthLayout ("room", layout));
  ASSERT_TRUE (agex::parseSynthLayout ("whole", layout));
  EXPECT_EQ (layout, agex::SynthLayout::Whole);
  // Defaults of whole scenes: cameras 0.6-2.5 m high, people 0.8-6 m away.
  agex::SynthOptions windowed = wholeOptions ();
  windowed.kinect_window = 9;
  const agex::SynthGenerator with_window (windowed);
  EXPECT_EQ (with_window.sensor ().kinect_window, 5) << "9 pixels at 640x480 are 5 at 320x240";
  const agex::SynthGenerator gen (wholeOptions ());
  EXPECT_EQ (gen.options ().min_height, 0.6);
  EXPECT_EQ (gen.options ().max_height, 2.5);
  EXPECT_EQ (gen.options ().min_distance, 0.8);
  EXPECT_EQ (gen.options ().max_distance, 6.0);
}

TEST (SynthWholeScenes, CamerasSpreadOverTheirRangesAndPeopleAreSeenOrCut)
{
  AGEX_REQUIRE_WHOLE_MOCAP ();
  agex::SynthOptions options = wholeOptions ();
  options.close_range_share = 0.0;
  options.background_removed_share = 0.0;
  const agex::SynthGenerator gen (options);
  const int w = gen.sensor ().width, h = gen.sensor ().height;
  double lowest_pitch = 90, highest_pitch = -90, lowest = 10, highest = 0;
  int cut_people = 0, outside_labels = 0, several = 0;
  for (std::uint64_t i = 0; i < 30; ++i)
  {
    const agex::SynthFrame frame = gen.render (i);
    double pitch, height;
    cameraPose (frame, pitch, height);
    // Roll turns the view axis not at all: the pitch is the drawn one.
    EXPECT_GE (pitch, -35.0 - 1e-6) << i;
    EXPECT_LE (pitch, 10.0 + 1e-6) << i;
    EXPECT_GE (height, 0.6 - 1e-6) << i;
    EXPECT_LE (height, 2.5 + 1e-6) << i;
    lowest_pitch = std::min (lowest_pitch, pitch);
    highest_pitch = std::max (highest_pitch, pitch);
    lowest = std::min (lowest, height);
    highest = std::max (highest, height);
    several += frame.people.size () > 1 ? 1 : 0;
    ASSERT_GE (frame.people.size (), 1u);
    EXPECT_LE (frame.people.size (), 4u);
    // Part labels only where a person's surface has depth.
    bool touches_border = false;
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u)
      {
        const std::size_t p = static_cast<std::size_t> (v) * w + u;
        if (frame.part_label[p] == 0)
          continue;
        ASSERT_TRUE (std::isfinite (frame.cloud[p].z)) << i;
        ASSERT_EQ (frame.object[p], agex::SynthObject::Person) << i;
        touches_border |= u == 0 || v == 0 || u == w - 1 || v == h - 1;
      }
    cut_people += touches_border ? 1 : 0;
    // A tip outside the image is never visible.
    for (const auto &label : frame.labels)
      if (label.tip_px.x () < 0 || label.tip_px.y () < 0 || label.tip_px.x () >= w || label.tip_px.y () >= h)
      {
        ++outside_labels;
        EXPECT_FALSE (label.visible) << i;
      }
  }
  EXPECT_LT (lowest_pitch, -20.0);
  EXPECT_GT (highest_pitch, 0.0);
  EXPECT_LT (lowest, 1.2);
  EXPECT_GT (highest, 1.9);
  EXPECT_GE (several, 10);
  EXPECT_GE (cut_people, 3) << "people cut by the frame's borders";
  EXPECT_GE (outside_labels, 3);
}

TEST (SynthWholeScenes, CloseRangeAndBackgroundRemovedFramesShowOnlyPeople)
{
  AGEX_REQUIRE_WHOLE_MOCAP ();
  agex::SynthOptions options = wholeOptions ();
  options.close_range_share = 1.0;
  const agex::SynthGenerator close (options);
  for (std::uint64_t i = 0; i < 4; ++i)
  {
    const agex::SynthFrame frame = close.render (i);
    ASSERT_EQ (frame.people.size (), 1u);
    EXPECT_GE (frame.people[0].distance, 0.7);
    EXPECT_LE (frame.people[0].distance, 1.6);
    EXPECT_FALSE (anyOf (frame, agex::SynthObject::Floor)) << i;
    EXPECT_FALSE (anyOf (frame, agex::SynthObject::Wall)) << i;
    EXPECT_TRUE (anyOf (frame, agex::SynthObject::Person)) << i;
  }
  options.close_range_share = 0.0;
  options.background_removed_share = 1.0;
  const agex::SynthGenerator removed (options);
  for (std::uint64_t i = 0; i < 4; ++i)
  {
    const agex::SynthFrame frame = removed.render (i);
    for (std::size_t p = 0; p < frame.cloud.size (); ++p)
    {
      if (std::isfinite (frame.cloud[p].z))
      {
        ASSERT_EQ (frame.object[p], agex::SynthObject::Person) << i;
      }
    }
    EXPECT_TRUE (anyOf (frame, agex::SynthObject::Person)) << i;
  }
}

TEST (SynthWholeScenes, ASmallerFrameIsTheSameSceneWithScaledIntrinsics)
{
  AGEX_REQUIRE_WHOLE_MOCAP ();
  agex::SynthOptions options = wholeOptions ();
  options.close_range_share = 0.0;
  options.background_removed_share = 0.0;
  options.width = options.height = 0;  // 640x480
  const agex::SynthGenerator full (options);
  options.width = 320;
  options.height = 240;
  const agex::SynthGenerator half (options);
  EXPECT_NEAR (half.sensor ().intrinsics.fx, 0.5 * full.sensor ().intrinsics.fx, 1e-9);
  EXPECT_EQ (half.datasetInfo ().width, 320);
  int compared = 0;
  for (std::uint64_t i = 0; i < 6; ++i)
  {
    const agex::SynthFrame a = full.render (i), b = half.render (i);
    ASSERT_EQ (a.people.size (), b.people.size ()) << i;
    for (std::size_t k = 0; k < a.people.size (); ++k)
      EXPECT_EQ (a.people[k].distance, b.people[k].distance) << i;
    EXPECT_TRUE (a.world_to_camera.isApprox (b.world_to_camera)) << i;
    // A person's pixels: a quarter as many at half the size.
    long person_a = 0, person_b = 0;
    for (const auto l : a.person_label)
      person_a += l != 0;
    for (const auto l : b.person_label)
      person_b += l != 0;
    if (person_a < 4000)
      continue;  // too few pixels for the ratio to settle
    ++compared;
    EXPECT_NEAR (static_cast<double> (person_b) / person_a, 0.25, 0.05) << i;
  }
  EXPECT_GE (compared, 2);
}

TEST (SynthWholeScenes, SameSeedSameFrames)
{
  AGEX_REQUIRE_WHOLE_MOCAP ();
  const agex::SynthGenerator a (wholeOptions ()), b (wholeOptions ());
  for (std::uint64_t i = 0; i < 3; ++i)
  {
    const agex::SynthFrame fa = a.render (i), fb = b.render (i);
    ASSERT_EQ (fa.cloud.size (), fb.cloud.size ());
    for (std::size_t p = 0; p < fa.cloud.size (); ++p)
    {
      const float za = fa.cloud[p].z, zb = fb.cloud[p].z;
      ASSERT_TRUE ((std::isnan (za) && std::isnan (zb)) || za == zb) << i << " " << p;
    }
    EXPECT_EQ (fa.part_label, fb.part_label);
  }
}
