// Synthetic frames with several people (SynthOptions::people, agex_synth --people): people
// placed apart are separate labelled regions, the nearer of two hides the farther, person
// ids agree between the label rows and the person image, a person at 5 m has the height
// in pixels the pinhole model gives, drawn people keep their distance ranges and do not
// intersect, and the same seed gives the same frames.

#include "test_support.h"

#include <agex/io/dataset.h>
#include <agex/simulation/synthetic_scene.h>

#include <map>
#include <memory>
#include <set>

namespace
{
using namespace agex_test;

#define AGEX_REQUIRE_MOCAP(path) AGEX_REQUIRE_SHARED_FILE (path, "the CMU motion capture (../shared/data/mocap)")

agex::SynthOptions
peopleOptions (agex::SynthSensor sensor, int people, bool clutter = true)
{
  agex::SynthOptions options;
  options.motion_files = {sharedData ("mocap/cmu_131_01.bvh"), sharedData ("mocap/cmu_02_01.bvh"),
                          sharedData ("mocap/cmu_05_06.bvh")};
  options.sensor = sensor;
  options.seed = 31;
  options.people = people;
  options.clutter = clutter;
  return options;
}

#define AGEX_REQUIRE_PEOPLE_MOCAP()                               \
  do                                                              \
  {                                                               \
    AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_131_01.bvh"));     \
    AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_02_01.bvh"));      \
    AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_05_06.bvh"));      \
  } while (0)

/** A person standing at a distance and bearing, facing the camera's way or not. */
agex::SynthPersonPlacement
at (double distance, double bearing, int subject = 0, double facing = 0.0)
{
  agex::SynthPersonPlacement p;
  p.clip = 0;  // cmu_131_01, a walk
  p.clip_frame = 40;
  p.subject = subject;
  p.distance = distance;
  p.bearing = bearing;
  p.facing = facing;
  return p;
}

/** Pixels per person id of a frame's person image. */
std::map<int, int>
personPixels (const agex::SynthFrame &frame)
{
  std::map<int, int> count;
  for (const auto id : frame.person_label)
    ++count[id];
  return count;
}

/** Size of the largest 4-connected region of one person id. */
int
largestRegion (const agex::SynthFrame &frame, int w, int h, int id)
{
  std::vector<char> seen (frame.person_label.size (), 0);
  int best = 0;
  for (std::size_t start = 0; start < seen.size (); ++start)
  {
    if (seen[start] || frame.person_label[start] != id)
      continue;
    int size = 0;
    std::vector<std::size_t> stack{start};
    seen[start] = 1;
    while (!stack.empty ())
    {
      const std::size_t i = stack.back ();
      stack.pop_back ();
      ++size;
      const int u = static_cast<int> (i % w), v = static_cast<int> (i / w);
      const int du[4] = {1, -1, 0, 0}, dv[4] = {0, 0, 1, -1};
      for (int q = 0; q < 4; ++q)
      {
        const int uu = u + du[q], vv = v + dv[q];
        if (uu < 0 || vv < 0 || uu >= w || vv >= h)
          continue;
        const std::size_t j = static_cast<std::size_t> (vv) * w + uu;
        if (!seen[j] && frame.person_label[j] == id)
        {
          seen[j] = 1;
          stack.push_back (j);
        }
      }
    }
    best = std::max (best, size);
  }
  return best;
}

TEST (SynthPeople, OptionsAreChecked)
{
  AGEX_REQUIRE_PEOPLE_MOCAP ();
  for (const int bad : {0, 5, -1})
    EXPECT_THROW (agex::SynthGenerator (peopleOptions (agex::SynthSensor::Kinect, bad)), std::invalid_argument) << bad;
  // Distances left at 0: 1.5-3.5 m for one person, 0.8-6 m for several.
  const agex::SynthGenerator one (peopleOptions (agex::SynthSensor::Kinect, 1));
  EXPECT_EQ (one.options ().min_distance, 1.5);
  EXPECT_EQ (one.options ().max_distance, 3.5);
  const agex::SynthGenerator three (peopleOptions (agex::SynthSensor::Kinect, 3));
  EXPECT_EQ (three.options ().min_distance, 0.8);
  EXPECT_EQ (three.options ().max_distance, 6.0);
  EXPECT_NE (three.datasetInfo ().provenance.find ("3 people per frame"), std::string::npos);
  EXPECT_EQ (one.datasetInfo ().provenance.find ("people per frame"), std::string::npos);
  EXPECT_TRUE (one.render (0).people.empty ());
  EXPECT_THROW (three.renderPeople (0, {}), std::invalid_argument);
  agex::SynthPersonPlacement bad = at (2.0, 0.0);
  bad.clip = 7;
  EXPECT_THROW (three.renderPeople (0, {bad}), std::invalid_argument);
}

TEST (SynthPeople, PeoplePlacedApartAreSeparateLabelledRegions)
{
  AGEX_REQUIRE_PEOPLE_MOCAP ();
  const agex::SynthGenerator gen (peopleOptions (agex::SynthSensor::Kinect, 3, false));
  const int w = gen.sensor ().width, h = gen.sensor ().height;
  const std::vector<agex::SynthPersonPlacement> people = {at (3.0, -0.4, 0), at (3.5, 0.0, 1, 1.0),
                                                          at (4.0, 0.4, 2, 2.5)};
  const agex::SynthFrame frame = gen.renderPeople (2, people);
  ASSERT_EQ (frame.people.size (), 3u);
  const auto count = personPixels (frame);
  EXPECT_EQ (count.size (), 4u) << "ids 0 (none) and 1-3";
  double mean_u[4] = {0, 0, 0, 0};
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
    {
      const int id = frame.person_label[static_cast<std::size_t> (v) * w + u];
      mean_u[id] += u;
      // No two people touch: a person pixel's 4-neighbours are that person or nothing.
      if (id && u + 1 < w)
      {
        const int right = frame.person_label[static_cast<std::size_t> (v) * w + u + 1];
        ASSERT_TRUE (right == 0 || right == id) << "(" << u << ", " << v << ")";
      }
      if (id && v + 1 < h)
      {
        const int below = frame.person_label[static_cast<std::size_t> (v + 1) * w + u];
        ASSERT_TRUE (below == 0 || below == id) << "(" << u << ", " << v << ")";
      }
    }
  for (int id = 1; id <= 3; ++id)
  {
    ASSERT_GT (count.at (id), 1000) << "person " << id;
    mean_u[id] /= count.at (id);
    // One region each (a few pixels may be cut off by the kinect's edge holes).
    EXPECT_GT (largestRegion (frame, w, h, id), 0.95 * count.at (id)) << "person " << id;
  }
  // Bearing -0.4 is on the image's left, +0.4 on its right.
  EXPECT_LT (mean_u[1], mean_u[2]);
  EXPECT_LT (mean_u[2], mean_u[3]);
  // Five label rows per person, person ids as placed.
  ASSERT_EQ (frame.labels.size (), 15u);
  for (std::size_t j = 0; j < frame.labels.size (); ++j)
    EXPECT_EQ (frame.labels[j].person, static_cast<int> (j / 5 + 1));
}

TEST (SynthPeople, TheNearerPersonHidesTheOneBehind)
{
  AGEX_REQUIRE_PEOPLE_MOCAP ();
  const agex::SynthGenerator gen (peopleOptions (agex::SynthSensor::Kinect, 2, false));
  const agex::SensorModel &sensor = gen.sensor ();
  // Person 2 stands 2 m behind person 1, 0.3 m to the side of the line of sight.
  const agex::SynthFrame frame = gen.renderPeople (5, {at (2.5, 0.0), at (4.5, 0.3 / 4.5, 1)});
  int hidden = 0, seen[3] = {0, 0, 0};
  for (int v = 0; v < sensor.height; ++v)
    for (int u = 0; u < sensor.width; ++u)
    {
      const std::size_t i = static_cast<std::size_t> (v) * sensor.width + u;
      const Eigen::Vector3d d =
          Eigen::Vector3d ((u - sensor.intrinsics.cx) / sensor.intrinsics.fx, (v - sensor.intrinsics.cy) / sensor.intrinsics.fy, 1.0)
              .normalized ();
      // Nearest hit per person, by brute force.
      double t_person[3] = {-1, -1, -1};
      for (const auto &p : frame.scene.primitives)
      {
        if (p.object != agex::SynthObject::Person)
          continue;
        const double t = p.intersect (Eigen::Vector3d::Zero (), d, 1e-6, nullptr);
        if (t > 0 && (t_person[p.person] < 0 || t < t_person[p.person]))
          t_person[p.person] = t;
      }
      const int id = frame.person_label[i];
      ++seen[id];
      if (t_person[1] > 0 && t_person[2] > 0)
      {
        ++hidden;  // both on this ray: person 2 is behind person 1 here
        ASSERT_NE (id, 2) << "a hidden surface is labelled, pixel (" << u << ", " << v << ")";
      }
      if (id == 2)
      {
        ASSERT_LT (t_person[1], 0) << "person 2 labelled where person 1 is in front";
      }
    }
  EXPECT_GT (hidden, 500) << "person 1 hides part of person 2";
  EXPECT_GT (seen[2], 500) << "and leaves part of person 2 in view";
  EXPECT_GT (seen[1], seen[2]);
}

/** Per sensor: drawn scenes of several people. */
class SynthPeopleSensors : public ::testing::TestWithParam<agex::SynthSensor>
{
};

TEST_P (SynthPeopleSensors, PersonIdsAgreeBetweenLabelRowsAndThePersonImage)
{
  AGEX_REQUIRE_PEOPLE_MOCAP ();
  const int n = 3;
  const agex::SynthGenerator gen (peopleOptions (GetParam (), n));
  const agex::SensorModel &sensor = gen.sensor ();
  const int win = agex::labelWindow (sensor);
  int visible = 0;
  std::set<int> seen_ids;
  for (std::uint64_t f = 0; f < 8; ++f)
  {
    const agex::SynthFrame frame = gen.render (f);
    const std::string where = "frame " + std::to_string (f);
    ASSERT_EQ (frame.people.size (), static_cast<std::size_t> (n)) << where;
    for (int k = 0; k + 1 < n; ++k)
      EXPECT_LE (frame.people[k].distance, frame.people[k + 1].distance) << where << ": person 1 is the nearest";
    // Five rows per person, in person order.
    ASSERT_EQ (frame.labels.size (), static_cast<std::size_t> (5 * n)) << where;
    std::map<int, int> rows;
    for (std::size_t j = 0; j < frame.labels.size (); ++j)
    {
      EXPECT_EQ (frame.labels[j].person, static_cast<int> (j / 5 + 1)) << where;
      ++rows[frame.labels[j].person];
    }
    // Every id of the image is a person with rows; every person primitive has its id.
    for (const auto &[id, pixels] : personPixels (frame))
    {
      if (id == 0)
        continue;
      seen_ids.insert (id);
      EXPECT_EQ (rows[id], 5) << where << ": person " << id << " is in the image but has no rows";
    }
    for (const auto &p : frame.scene.primitives)
      if (p.object == agex::SynthObject::Person)
      {
        EXPECT_TRUE (p.person >= 1 && p.person <= n) << where;
      }
    // A visible tip shows its own person near its pixel.
    for (const auto &l : frame.labels)
    {
      if (!l.visible)
        continue;
      ++visible;
      const long u = std::lround (l.tip_px.x ()), v = std::lround (l.tip_px.y ());
      bool own = false;
      for (long vv = std::max (0L, v - win); vv <= std::min<long> (sensor.height - 1, v + win); ++vv)
        for (long uu = std::max (0L, u - win); uu <= std::min<long> (sensor.width - 1, u + win); ++uu)
          own = own || frame.person_label[static_cast<std::size_t> (vv) * sensor.width + uu] == l.person;
      EXPECT_TRUE (own) << where << ": " << agex::bodyPartName (l.part) << " of person " << l.person
                        << " is visible but its pixel shows no pixel of that person";
    }
  }
  // Many tips are hidden (behind people, out of the frame, beyond sr4000's 5 m and the
  // bonn steps' 4.1 m), but some are seen.
  EXPECT_GT (visible, 15);
  EXPECT_GE (seen_ids.size (), 2u);
}

// Drawn people stand within the distance range (uniform), within the field of view or
// in line with another person, and never inside each other.
TEST_P (SynthPeopleSensors, DrawnPeopleKeepTheirRangesAndDoNotIntersect)
{
  AGEX_REQUIRE_PEOPLE_MOCAP ();
  const agex::SynthGenerator gen (peopleOptions (GetParam (), 4));
  const agex::SensorModel &sensor = gen.sensor ();
  const double half_fov = std::atan (0.5 * sensor.width / sensor.intrinsics.fx);
  int in_line = 0, near = 0, far = 0;
  for (std::uint64_t f = 0; f < 40; ++f)
  {
    const auto people = gen.drawPeople (f);
    ASSERT_EQ (people.size (), 4u);
    for (std::size_t k = 0; k < people.size (); ++k)
    {
      const agex::SynthPersonPlacement &p = people[k];
      EXPECT_GE (p.distance, 0.8);
      EXPECT_LE (p.distance, 6.0) << "beyond the range only when no spot of the range is free";
      near += p.distance < 2.0;
      far += p.distance > 4.0;
      // In the field of view, or in line with another person: at most 0.5 m off the
      // other's line of sight at its own distance.
      bool with_other = false;
      for (std::size_t j = 0; j < people.size (); ++j)
        with_other = with_other || (j != k && std::abs (p.bearing - people[j].bearing) * p.distance <= 0.5 + 1e-9);
      in_line += with_other;
      EXPECT_TRUE (std::abs (p.bearing) <= 0.85 * half_fov + 1e-9 || with_other) << "frame " << f;
    }
  }
  EXPECT_GT (near, 20);
  EXPECT_GT (far, 40);
  EXPECT_GT (in_line, 40) << "some people stand in line with another";
  // Capsule bodies of different people are apart: no point of one's capsule axes is
  // within the other's capsules by more than the axis' own radius.
  for (std::uint64_t f = 0; f < 4; ++f)
  {
    const agex::SynthFrame frame = gen.render (f);
    for (const auto &a : frame.scene.primitives)
    {
      if (a.object != agex::SynthObject::Person || a.shape != agex::SynthPrimitive::Shape::Capsule)
        continue;
      for (const auto &b : frame.scene.primitives)
      {
        if (b.object != agex::SynthObject::Person || b.person == a.person ||
            b.shape != agex::SynthPrimitive::Shape::Capsule)
          continue;
        for (int s = 0; s <= 20; ++s)
          ASSERT_GT (b.distance (a.a + (a.b - a.a) * (s / 20.0)), a.radius)
              << "frame " << f << ": persons " << int (a.person) << " and " << int (b.person) << " intersect";
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P (Synth, SynthPeopleSensors,
                          ::testing::Values (agex::SynthSensor::Sr4000, agex::SynthSensor::Kinect,
                                             agex::SynthSensor::Bonn),
                          [] (const ::testing::TestParamInfo<agex::SynthSensor> &info) {
                            return std::string (agex::synthSensorName (info.param));
                          });

// The pinhole model: a person H tall at distance d is fy H / d pixels tall.
TEST (SynthPeople, APersonAtFiveMetresHasTheExpectedPixelHeight)
{
  AGEX_REQUIRE_PEOPLE_MOCAP ();
  for (const auto &[sensor, distance] :
       {std::pair{agex::SynthSensor::Kinect, 5.0}, std::pair{agex::SynthSensor::Sr4000, 4.5}})
  {
    const agex::SynthGenerator gen (peopleOptions (sensor, 1, false));
    const agex::SynthPersonPlacement p = at (distance, 0.0);
    const agex::BodyModel body = gen.body (p.clip, p.clip_frame, p.subject);
    const agex::SynthFrame frame = gen.renderPeople (1, {p});
    int top = gen.sensor ().height, bottom = -1;
    for (int v = 0; v < gen.sensor ().height; ++v)
      for (int u = 0; u < gen.sensor ().width; ++u)
        if (frame.person_label[static_cast<std::size_t> (v) * gen.sensor ().width + u] == 1)
        {
          top = std::min (top, v);
          bottom = std::max (bottom, v);
        }
    ASSERT_GE (bottom, top) << agex::synthSensorName (sensor) << ": the person is not in the frame";
    const double expected = gen.sensor ().intrinsics.fy * (body.highest - body.lowest) / distance;
    EXPECT_NEAR (bottom - top + 1, expected, 0.1 * expected)
        << agex::synthSensorName (sensor) << " at " << distance << " m";
  }
}

TEST (SynthPeople, RenderIsRenderPeopleOfTheDrawnPeopleAndDeterministic)
{
  AGEX_REQUIRE_PEOPLE_MOCAP ();
  const agex::SynthGenerator gen (peopleOptions (agex::SynthSensor::Sr4000, 3));
  const agex::SynthFrame a = gen.render (6), b = gen.renderPeople (6, gen.drawPeople (6)), c = gen.render (6),
                         d = gen.render (7);
  ASSERT_EQ (a.cloud.size (), b.cloud.size ());
  bool differs = false;
  for (std::size_t i = 0; i < a.cloud.size (); ++i)
  {
    ASSERT_EQ (bits (a.cloud.points[i].z), bits (b.cloud.points[i].z)) << i;
    ASSERT_EQ (bits (a.cloud.points[i].z), bits (c.cloud.points[i].z)) << i;
    differs = differs || bits (a.cloud.points[i].z) != bits (d.cloud.points[i].z);
  }
  EXPECT_TRUE (differs);
  EXPECT_EQ (a.person_label, b.person_label);
  EXPECT_EQ (a.part_label, c.part_label);
  std::set<int> clips;
  for (const auto &p : a.people)
    clips.insert (p.clip);
  EXPECT_EQ (std::count (a.sequence.begin (), a.sequence.end (), '+') + 1, static_cast<long> (clips.size ()))
      << "the sequence names every motion of the frame: " << a.sequence;
}

TEST (SynthPeople, DatasetRowsCarryThePerson)
{
  AGEX_REQUIRE_PEOPLE_MOCAP ();
  QuietPcl quiet;
  TempDir dir;
  const agex::SynthGenerator gen (peopleOptions (agex::SynthSensor::Bonn, 2));
  const agex::SynthRunStats stats = agex::writeSyntheticDataset (gen, 3, dir.file ("two"), false);
  EXPECT_EQ (stats.labels, 30);
  const std::string csv = readAll (dir.file ("two/labels.csv"));
  EXPECT_EQ (csv.substr (0, csv.find ('\n')).substr (csv.find ('\n') - 7), ",person");
  const agex::Dataset ds = agex::Dataset::read (dir.file ("two"));
  for (const auto &frame : ds.frames ())
  {
    const auto labels = ds.labelsOf (frame.id);
    ASSERT_EQ (labels.size (), 10u);
    std::map<int, int> per_person;
    for (const auto &l : labels)
      ++per_person[l.person];
    EXPECT_EQ (per_person[1], 5);
    EXPECT_EQ (per_person[2], 5);
    const cv::Mat persons = ds.loadPersonLabels (frame.id);
    double lo = 0, hi = 0;
    cv::minMaxLoc (persons, &lo, &hi);
    EXPECT_LE (hi, 2.0);
    EXPECT_NE (frame.sequence, "");
  }
}
}  // namespace
