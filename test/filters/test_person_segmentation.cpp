// agex::PersonSegmentation: synthetic rooms rendered by ray casting (people side by side,
// apart and touching, a person cut in two by a railing in front, furniture without anyone,
// a person at 5 m, people without a floor in view, a person cut by the image's border, a
// floor seen only far away, the feet at the floor), the floor-free rule on Skeltrack's upper
// bodies, PCL's five_people frame, Bonn frames at their distance and moved 1-2 m back, and
// misuse.

#include "test_support.h"

#include <agex/filters/person_segmentation.h>
#include <agex/filters/surface_segmentation.h>
#include <agex/io/bonn.h>
#include <agex/io/frame_io.h>

#include <pcl/common/io.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <vector>

namespace
{
using agex_test::Cloud;
using Segmentation = agex::PersonSegmentation<pcl::PointXYZ>;

/** A pinhole depth camera: Kinect geometry by default. */
struct DepthCamera
{
  int width = 640, height = 480;
  double f = 525.0, cx = 319.5, cy = 239.5;

  /** The same field of view at another resolution. */
  DepthCamera scaled (int new_width) const
  {
    DepthCamera c;
    const double s = static_cast<double> (new_width) / width;
    c.width = new_width;
    c.height = static_cast<int> (std::lround (height * s));
    c.f = f * s;
    c.cx = (cx + 0.5) * s - 0.5;
    c.cy = (cy + 0.5) * s - 0.5;
    return c;
  }
};

enum class Pose
{
  ArmsDown,
  ArmsRaised,  ///< "goalpost": upper arms out level with the shoulders, forearms up
  Seated,      ///< on a seat 0.45 m high, thighs towards the camera, hands on them
  SideOn       ///< arms down, walking across the view: seen from the side, a slim body
};

/** A room of spheres, capsules and boxes over a level floor, in camera coordinates (x
  * right, y down, z forward; the floor is y = camera_height). Heights are above the floor. */
struct Scene
{
  struct Sphere
  {
    Eigen::Vector3d c;
    double r;
  };
  struct Capsule
  {
    Eigen::Vector3d a, b;
    double r;
  };
  struct Box
  {
    Eigen::Vector3d lo, hi;
  };

  double camera_height = 1.0;
  bool floor = true;
  double noise = 0.0015;  ///< depth noise c z^2 (Kinect), metres
  std::vector<Sphere> spheres;
  std::vector<Capsule> capsules;
  std::vector<Box> boxes;

  Eigen::Vector3d at (double x, double height, double z) const { return {x, camera_height - height, z}; }

  /** An axis-aligned box: x0..x1 across, h0..h1 high, z0..z1 deep. */
  void addBox (double x0, double x1, double h0, double h1, double z0, double z1)
  {
    boxes.push_back ({at (x0, h1, z0), at (x1, h0, z1)});
  }

  /** A person of the given height standing at (x, z), facing the camera. */
  void addPerson (double x, double z, double height = 1.75, Pose pose = Pose::ArmsDown)
  {
    const double s = height / 1.75;
    // Seen from the side, the body's sideways offsets point away from the camera.
    const bool side_on = pose == Pose::SideOn;
    auto P = [&] (double dx, double h, double dz = 0.0) {
      return side_on ? at (x + dz * s, h * s, z + dx * s) : at (x + dx * s, h * s, z + dz * s);
    };
    const double torso = side_on ? 0.11 : 0.14;  // radius of each half
    if (pose == Pose::Seated)
    {
      spheres.push_back ({P (0, 1.2), 0.105 * s});  // head: top at 1.3 m
      capsules.push_back ({P (0, 1.02), P (0, 1.12), 0.055 * s});
      capsules.push_back ({P (-0.08, 0.68), P (-0.08, 0.9), 0.14 * s});
      capsules.push_back ({P (0.08, 0.68), P (0.08, 0.9), 0.14 * s});
      capsules.push_back ({P (-0.09, 0.55), P (0.09, 0.55), 0.12 * s});
      for (const double side : {-1.0, 1.0})
      {
        capsules.push_back ({P (0.1 * side, 0.5), P (0.1 * side, 0.5, -0.42), 0.07 * s});            // thigh
        capsules.push_back ({P (0.1 * side, 0.5, -0.42), P (0.1 * side, 0.1, -0.42), 0.06 * s});     // shin
        capsules.push_back ({P (0.1 * side, 0.05, -0.42), P (0.1 * side, 0.05, -0.58), 0.045 * s});  // foot
        capsules.push_back ({P (0.24 * side, 0.97), P (0.26 * side, 0.68, -0.05), 0.05 * s});        // upper arm
        capsules.push_back ({P (0.26 * side, 0.68, -0.05), P (0.2 * side, 0.6, -0.32), 0.045 * s});  // forearm
      }
      return;
    }
    spheres.push_back ({P (0, 1.625), 0.105 * s});                 // head: top at 1.73 m
    capsules.push_back ({P (0, 1.44), P (0, 1.55), 0.055 * s});    // neck
    capsules.push_back ({P (-0.08, 1.1), P (-0.08, 1.32), torso * s});  // torso, two halves
    capsules.push_back ({P (0.08, 1.1), P (0.08, 1.32), torso * s});
    capsules.push_back ({P (-0.09, 0.95), P (0.09, 0.95), 0.12 * s});  // hips
    for (const double side : {-1.0, 1.0})
    {
      capsules.push_back ({P (0.1 * side, 0.9), P (0.1 * side, 0.1), 0.07 * s});              // leg
      capsules.push_back ({P (0.1 * side, 0.05), P (0.1 * side, 0.05, -0.16), 0.045 * s});    // foot
      if (pose == Pose::ArmsDown || side_on)
        capsules.push_back ({P (0.24 * side, 1.4), P (0.28 * side, 0.8), 0.05 * s});
      else
      {
        capsules.push_back ({P (0.24 * side, 1.4), P (0.48 * side, 1.42), 0.05 * s});
        capsules.push_back ({P (0.48 * side, 1.42), P (0.48 * side, 1.78), 0.05 * s});
      }
    }
  }

  /** A desk: a top at 0.75 m on four legs. */
  void addDesk (double x0, double x1, double z0, double z1)
  {
    addBox (x0, x1, 0.72, 0.75, z0, z1);
    for (const double x : {x0, x1 - 0.05})
      for (const double z : {z0, z1 - 0.05})
        addBox (x, x + 0.05, 0.0, 0.72, z, z + 0.05);
  }

  /** A chair facing the camera: seat at 0.45 m, backrest up to back_top. */
  void addChair (double x, double z, double back_top = 1.0)
  {
    addBox (x - 0.23, x + 0.23, 0.42, 0.46, z - 0.22, z + 0.22);
    addBox (x - 0.23, x + 0.23, 0.46, back_top, z + 0.18, z + 0.22);
    for (const double dx : {-0.23, 0.19})
      for (const double dz : {-0.22, 0.18})
        addBox (x + dx, x + dx + 0.04, 0.0, 0.42, z + dz, z + dz + 0.04);
  }

  /** Nearest hit along the unit ray d from the camera centre, as a distance (inf: none). */
  double trace (const Eigen::Vector3d &d) const
  {
    double best = std::numeric_limits<double>::infinity ();
    if (floor && d.y () > 1e-9)
      best = camera_height / d.y ();
    for (const auto &sphere : spheres)
    {
      const double b = d.dot (sphere.c), c = sphere.c.squaredNorm () - sphere.r * sphere.r, h = b * b - c;
      if (h >= 0.0 && b - std::sqrt (h) > 0.0)
        best = std::min (best, b - std::sqrt (h));
    }
    for (const auto &cap : capsules)
    {
      // Ray-capsule intersection (closed form: the cylinder, then the end caps).
      const Eigen::Vector3d ba = cap.b - cap.a, oa = -cap.a;
      const double baba = ba.dot (ba), bard = ba.dot (d), baoa = ba.dot (oa), rdoa = d.dot (oa), oaoa = oa.dot (oa);
      const double a = baba - bard * bard, b = baba * rdoa - baoa * bard;
      const double c = baba * oaoa - baoa * baoa - cap.r * cap.r * baba;
      double h = b * b - a * c;
      if (h < 0.0 || a <= 0.0)
        continue;
      const double t = (-b - std::sqrt (h)) / a, y = baoa + t * bard;
      if (y > 0.0 && y < baba)
      {
        if (t > 0.0)
          best = std::min (best, t);
        continue;
      }
      const Eigen::Vector3d oc = y <= 0.0 ? oa : Eigen::Vector3d (-cap.b);
      const double bb = d.dot (oc), cc = oc.dot (oc) - cap.r * cap.r;
      h = bb * bb - cc;
      if (h > 0.0 && -bb - std::sqrt (h) > 0.0)
        best = std::min (best, -bb - std::sqrt (h));
    }
    for (const auto &box : boxes)
    {
      double t0 = 0.0, t1 = std::numeric_limits<double>::infinity ();
      bool hit = true;
      for (int k = 0; k < 3 && hit; ++k)
      {
        if (std::abs (d[k]) < 1e-12)
        {
          hit = box.lo[k] <= 0.0 && 0.0 <= box.hi[k];
          continue;
        }
        double a = box.lo[k] / d[k], b = box.hi[k] / d[k];
        if (a > b)
          std::swap (a, b);
        t0 = std::max (t0, a);
        t1 = std::min (t1, b);
        hit = t0 <= t1;
      }
      if (hit && t0 > 0.0)
        best = std::min (best, t0);
    }
    return best;
  }

  /** The organized cloud the camera sees (up to 10 m), with seeded depth noise. */
  Cloud::Ptr render (const DepthCamera &cam, unsigned seed = 1) const
  {
    Cloud::Ptr cloud = agex_test::nanCloud (cam.width, cam.height);
    std::mt19937 rng (seed);
    std::normal_distribution<double> gauss (0.0, 1.0);
    for (int v = 0; v < cam.height; ++v)
      for (int u = 0; u < cam.width; ++u)
      {
        const Eigen::Vector3d ray ((u - cam.cx) / cam.f, (v - cam.cy) / cam.f, 1.0);
        const double t = trace (ray.normalized ());
        if (!std::isfinite (t))
          continue;
        double z = t * ray.normalized ().z ();
        if (z > 10.0)
          continue;
        z += noise * z * z * gauss (rng);
        (*cloud) (u, v) = pcl::PointXYZ (static_cast<float> (ray.x () * z), static_cast<float> (ray.y () * z),
                                         static_cast<float> (z));
      }
    return cloud;
  }
};

struct Found
{
  std::vector<pcl::PointIndices> persons;
  std::vector<agex::PersonInfo> infos;
  pcl::PointCloud<pcl::Label> labels;
};

Found
segment (const Cloud::ConstPtr &cloud, Segmentation *configured = nullptr)
{
  Segmentation own;
  Segmentation &seg = configured ? *configured : own;
  seg.setInputCloud (cloud);
  Found found;
  seg.segment (found.labels, found.persons);
  found.infos = seg.getPersons ();
  return found;
}

/** Mean column of a person's pixels. */
double
meanColumn (const Cloud &cloud, const pcl::PointIndices &person)
{
  double sum = 0.0;
  for (const auto i : person.indices)
    sum += i % cloud.width;
  return person.indices.empty () ? -1.0 : sum / person.indices.size ();
}

/** Pixels of a scene's person: rendered alone, the same camera, no floor, no noise. */
std::vector<unsigned char>
personMask (double x, double z, const DepthCamera &cam, Pose pose = Pose::ArmsDown)
{
  Scene alone;
  alone.floor = false;
  alone.noise = 0.0;
  alone.addPerson (x, z, 1.75, pose);
  const Cloud::Ptr cloud = alone.render (cam);
  std::vector<unsigned char> mask (cloud->size (), 0);
  for (std::size_t i = 0; i < cloud->size (); ++i)
    mask[i] = std::isfinite ((*cloud)[i].z);
  return mask;
}

/** A person's points lower (higher) than the given height above the floor (the scenes'
  * camera is 1 m above it). */
long
pointsBelow (const Cloud &cloud, const pcl::PointIndices &person, double height)
{
  return std::count_if (person.indices.begin (), person.indices.end (),
                        [&] (int i) { return 1.0 - cloud[i].y < height; });
}

long
pointsAbove (const Cloud &cloud, const pcl::PointIndices &person, double height)
{
  return std::count_if (person.indices.begin (), person.indices.end (),
                        [&] (int i) { return 1.0 - cloud[i].y > height; });
}

/** Fraction of mask covered by the person, and of the person inside the mask. */
void
overlap (const pcl::PointIndices &person, const std::vector<unsigned char> &mask, double &recall, double &precision)
{
  const auto in_mask = std::count_if (person.indices.begin (), person.indices.end (), [&] (int i) { return mask[i]; });
  recall = static_cast<double> (in_mask) / std::max<std::size_t> (1, std::count (mask.begin (), mask.end (), 1));
  precision = static_cast<double> (in_mask) / std::max<std::size_t> (1, person.indices.size ());
}
}  // namespace

// ---------------------------------------------------------------------------------------
// Synthetic rooms

TEST (PersonSegmentation, OnePersonIsOnePersonWithItsPixels)
{
  Scene scene;
  scene.addPerson (0.1, 3.0);
  const DepthCamera cam;
  const Cloud::Ptr cloud = scene.render (cam);
  Segmentation seg;
  const Found found = segment (cloud, &seg);
  ASSERT_EQ (found.persons.size (), 1u);
  EXPECT_TRUE (seg.getFloorFound ());
  EXPECT_NEAR (seg.getFloorPlane ()[3], 1.0, 0.03);  // the camera is 1 m above the floor
  EXPECT_NEAR (seg.getUsedFocalLengthX (), 525.0, 1.0);
  double recall, precision;
  overlap (found.persons[0], personMask (0.1, 3.0, cam), recall, precision);
  EXPECT_GT (recall, 0.95);  // all but the soles (within the floor margin)
  EXPECT_GT (precision, 0.99);
  const agex::PersonInfo &info = found.infos[0];
  EXPECT_TRUE (info.on_floor);
  EXPECT_FALSE (info.too_far);
  EXPECT_FALSE (info.split);
  EXPECT_NEAR (info.top, 1.73, 0.05);
  EXPECT_NEAR (info.distance, 3.0, 0.2);
  EXPECT_NEAR (info.ground.z (), 3.0, 0.2);
  EXPECT_NEAR (info.ground.y (), 1.0, 0.03);  // on the floor
  EXPECT_EQ (info.points, static_cast<int> (found.persons[0].indices.size ()));
  // Labels and indices agree; indices are sorted.
  EXPECT_TRUE (std::is_sorted (found.persons[0].indices.begin (), found.persons[0].indices.end ()));
  std::size_t labelled = 0;
  for (const auto &l : found.labels)
    labelled += l.label == 0;
  EXPECT_EQ (labelled, found.persons[0].indices.size ());
}

TEST (PersonSegmentation, TwoPeopleSideBySideAreTwoPersons)
{
  const DepthCamera cam;
  for (const double half_gap : {0.45, 0.3})  // hands apart; hands and arms overlapping
  {
    SCOPED_TRACE (half_gap);
    Scene scene;
    scene.addPerson (-half_gap, 3.0);
    scene.addPerson (half_gap, 3.0);
    const Cloud::Ptr cloud = scene.render (cam);
    const Found found = segment (cloud);
    ASSERT_EQ (found.persons.size (), 2u);
    // One on each side, each mostly its own pixels.
    const bool first_left = meanColumn (*cloud, found.persons[0]) < meanColumn (*cloud, found.persons[1]);
    const auto left = personMask (-half_gap, 3.0, cam), right = personMask (half_gap, 3.0, cam);
    for (int k = 0; k < 2; ++k)
    {
      double recall, precision;
      overlap (found.persons[k], (k == 0) == first_left ? left : right, recall, precision);
      EXPECT_GT (recall, 0.85) << "person " << k;
      EXPECT_GT (precision, 0.9) << "person " << k;
      EXPECT_NEAR (found.infos[k].ground.x (), (k == 0) == first_left ? -half_gap : half_gap, 0.12);
    }
    // Touching, they were one cluster, cut between the heads.
    EXPECT_EQ (found.infos[0].split, half_gap < 0.4);
  }
}

TEST (PersonSegmentation, RaisedArmsBesideTheHeadAreNoSecondPerson)
{
  Scene scene;
  scene.addPerson (0.0, 2.5, 1.75, Pose::ArmsRaised);
  const DepthCamera cam;
  const Found found = segment (scene.render (cam));
  ASSERT_EQ (found.persons.size (), 1u);
  EXPECT_FALSE (found.infos[0].split);
  double recall, precision;
  overlap (found.persons[0], personMask (0.0, 2.5, cam, Pose::ArmsRaised), recall, precision);
  EXPECT_GT (recall, 0.95);
}

TEST (PersonSegmentation, SlimPersonSeenFromTheSideIsAPerson)
{
  // Across the view the head (0.21 m) is nearly as wide as the slim body below it (0.22 m
  // through chest and back; the measurement's bins round both): the narrow-top rule by
  // ratio alone took it for a cabinet at most of these places.
  const DepthCamera cam;
  int by_ratio_found = 0, places = 0;
  for (const double z : {1.8, 2.2, 3.0, 4.0})
    for (const double x : {-0.3, 0.3})
    {
      SCOPED_TRACE ("at x " + std::to_string (x) + " m, z " + std::to_string (z) + " m");
      Scene scene;
      scene.addPerson (x, z, 1.75, Pose::SideOn);
      const Cloud::Ptr cloud = scene.render (cam);
      Segmentation seg;
      const Found found = segment (cloud, &seg);
      ASSERT_EQ (found.persons.size (), 1u);
      double recall, precision;
      overlap (found.persons[0], personMask (x, z, cam, Pose::SideOn), recall, precision);
      EXPECT_GT (recall, 0.9);
      EXPECT_GT (precision, 0.99);
      Segmentation by_ratio;
      by_ratio.setCrownLimits (by_ratio.getCrownDrop (), by_ratio.getMaxCrownRatio (), 0.f);
      by_ratio_found += segment (cloud, &by_ratio).persons.size () == 1;
      ++places;
    }
  EXPECT_LT (by_ratio_found, places / 2);
}

TEST (PersonSegmentation, SeatedPersonOnAChairIsOnePerson)
{
  Scene scene;
  scene.addChair (0.2, 3.05, 0.95);  // the backrest just behind the person's back
  scene.addPerson (0.2, 2.85, 1.75, Pose::Seated);
  scene.addDesk (-1.5, -0.5, 2.5, 3.1);
  const DepthCamera cam;
  const Cloud::Ptr cloud = scene.render (cam);
  const Found found = segment (cloud);
  ASSERT_EQ (found.persons.size (), 1u);
  EXPECT_NEAR (found.infos[0].top, 1.3, 0.08);
  double recall, precision;
  overlap (found.persons[0], personMask (0.2, 2.85, cam, Pose::Seated), recall, precision);
  EXPECT_GT (recall, 0.9);
  EXPECT_GT (precision, 0.8);  // some of the chair may come with the person
}

TEST (PersonSegmentation, PersonCutInTwoByARailingInFrontIsOnePerson)
{
  // A railing 0.6 m in front hides the person from 0.7 to 0.85 m: the legs below are a
  // piece of their own, apart from the body by the railing's depth gap.
  Scene scene;
  scene.addPerson (0.0, 3.0);
  scene.addBox (-1.5, 1.5, 0.7, 0.85, 2.4, 2.45);
  const DepthCamera cam;
  const Cloud::Ptr cloud = scene.render (cam);
  const Found found = segment (cloud);
  ASSERT_EQ (found.persons.size (), 1u);
  EXPECT_GE (found.infos[0].pieces, 2);
  // Legs and upper body both belong to it; the railing does not.
  EXPECT_GT (pointsBelow (*cloud, found.persons[0], 0.6), 2000);
  EXPECT_GT (pointsAbove (*cloud, found.persons[0], 1.0), 8000);
  const auto &ids = found.persons[0].indices;
  EXPECT_EQ (std::count_if (ids.begin (), ids.end (), [&] (int i) { return (*cloud)[i].z < 2.6; }), 0);
}

TEST (PersonSegmentation, PersonWhoseHipsAreHiddenIsOnePerson)
{
  // A board 1 m in front hides the person from 0.75 to 1.25 m: above it the upper body
  // floats (its lowest point above 1.1 m), below it the legs are too low to be anyone; each
  // is nobody alone, together they are the person.
  Scene scene;
  scene.addPerson (0.0, 3.0);
  scene.addBox (-0.6, 0.6, 0.75, 1.25, 2.0, 2.05);
  const DepthCamera cam;
  const Cloud::Ptr cloud = scene.render (cam);
  const Found found = segment (cloud);
  ASSERT_EQ (found.persons.size (), 1u);
  EXPECT_GE (found.infos[0].pieces, 2);
  double recall, precision;
  overlap (found.persons[0], personMask (0.0, 3.0, cam), recall, precision);
  EXPECT_GT (precision, 0.99);  // not the board
  EXPECT_GT (pointsBelow (*cloud, found.persons[0], 0.7), 1000);  // legs
  EXPECT_GT (pointsAbove (*cloud, found.persons[0], 1.3), 2000);  // upper body
}

TEST (PersonSegmentation, PersonSeenOnlyRoundANearerOneIsAHiddenPerson)
{
  // Someone 1-1.5 m behind another and a little to the side: only their head and a strip of
  // the body show beside the nearer one, in pieces that are nobody by the rules of whole
  // persons. Kept as one hidden person; without the rule, only the nearer one is found.
  for (const double z : {3.0, 3.5})
  {
    Scene scene;
    scene.addBox (-4.0, 4.0, 0.0, 2.6, 5.5, 5.6);
    scene.addPerson (0.0, 2.0);
    scene.addPerson (0.3, z);
    const DepthCamera cam;
    const Cloud::Ptr cloud = scene.render (cam);
    const Found found = segment (cloud);
    ASSERT_EQ (found.persons.size (), 2u) << "at " << z << " m";
    EXPECT_FALSE (found.infos[0].hidden);
    EXPECT_TRUE (found.infos[1].hidden);
    EXPECT_NEAR (found.infos[1].distance, z, 0.15);
    // The hidden person's pixels are what shows of the one behind.
    const std::vector<unsigned char> behind = personMask (0.3, z, cam);
    const std::vector<unsigned char> front = personMask (0.0, 2.0, cam);
    std::vector<unsigned char> visible (behind.size ());
    for (std::size_t i = 0; i < behind.size (); ++i)
      visible[i] = behind[i] && !front[i];
    double recall, precision;
    overlap (found.persons[1], visible, recall, precision);
    EXPECT_GT (precision, 0.95);
    EXPECT_GT (recall, 0.7);

    Segmentation off;
    off.setHiddenPersons (false, off.getHiddenPersonMinArea ());
    const Found without = segment (cloud, &off);
    ASSERT_EQ (without.persons.size (), 1u);
    EXPECT_FALSE (without.infos[0].hidden);
  }
}

TEST (PersonSegmentation, BoardAndLowCabinetBehindPeopleAreNoHiddenPerson)
{
  // A board seen in the gap between two people (hemmed in by them: the background rule) and
  // a low cabinet beside and behind a person (nothing as high as a person's top: the top
  // rule) are no one, though each is a piece behind a person.
  Scene board;
  board.addBox (-4.0, 4.0, 0.0, 2.6, 5.5, 5.6);
  board.addPerson (-0.4, 2.0);
  board.addPerson (0.4, 2.0);
  board.addBox (-0.25, 0.25, 0.3, 1.6, 3.5, 3.52);
  const DepthCamera cam;
  const Found two = segment (board.render (cam));
  ASSERT_EQ (two.persons.size (), 2u);
  for (const auto &info : two.infos)
    EXPECT_FALSE (info.hidden);

  Scene cabinet;
  cabinet.addBox (-4.0, 4.0, 0.0, 2.6, 5.5, 5.6);
  cabinet.addPerson (0.0, 2.0);
  cabinet.addBox (0.3, 0.8, 0.0, 0.5, 3.2, 3.5);
  const Found one = segment (cabinet.render (cam));
  ASSERT_EQ (one.persons.size (), 1u);
  EXPECT_FALSE (one.infos[0].hidden);
}

TEST (PersonSegmentation, WallDeskChairAndCabinetAreNoPerson)
{
  Scene scene;
  scene.addBox (-3.0, 3.0, 0.0, 2.6, 5.0, 5.1);  // back wall
  scene.addBox (-2.2, -2.1, 0.0, 2.6, 2.0, 5.0); // side wall
  scene.addDesk (-1.3, -0.1, 2.4, 3.0);
  scene.addChair (0.5, 2.6, 1.0);
  scene.addChair (1.3, 3.4, 1.15);  // a high-backed one
  scene.addBox (1.6, 2.1, 0.0, 1.8, 4.2, 4.6);  // a cabinet
  const DepthCamera cam;
  const Cloud::Ptr cloud = scene.render (cam);
  const Found found = segment (cloud);
  EXPECT_EQ (found.persons.size (), 0u);

  // And with someone among them, only that one, without the furniture.
  scene.addPerson (-0.2, 3.8);
  const Cloud::Ptr with_person = scene.render (cam);
  const Found one = segment (with_person);
  ASSERT_EQ (one.persons.size (), 1u);
  double recall, precision;
  overlap (one.persons[0], personMask (-0.2, 3.8, cam), recall, precision);
  EXPECT_GT (precision, 0.97);
  EXPECT_GT (recall, 0.6);  // the desk hides part of the legs
}

TEST (PersonSegmentation, PersonAtFiveMetresIsFoundAndNotTooFar)
{
  Scene scene;
  scene.addBox (-4.0, 4.0, 0.0, 2.6, 7.0, 7.1);
  scene.addPerson (0.4, 5.0);
  const DepthCamera cam;
  const Cloud::Ptr cloud = scene.render (cam);
  const Found found = segment (cloud);
  ASSERT_EQ (found.persons.size (), 1u);
  const agex::PersonInfo &info = found.infos[0];
  EXPECT_NEAR (info.distance, 5.0, 0.2);
  EXPECT_NEAR (info.top, 1.73, 0.12);
  // A 0.01 m^2 hand at 5 m covers 0.01 * 525^2 / 25 = 110 pixels: enough.
  EXPECT_NEAR (info.hand_pixels, 110.0, 10.0);
  EXPECT_FALSE (info.too_far);
  // All of it, down to the feet: the floor margin is the height noise (3 x 3.75 cm of depth
  // noise seen 1 m above the floor from 5 m away is 2.3 cm of height), not the depth noise.
  double recall, precision;
  overlap (found.persons[0], personMask (0.4, 5.0, cam), recall, precision);
  EXPECT_GT (recall, 0.95);
  EXPECT_GT (precision, 0.98);
  EXPECT_GT (pointsBelow (*cloud, found.persons[0], 0.08), 40);

  // The same scene seen at 160x120: the hand has 7 pixels, too few.
  const DepthCamera small = cam.scaled (160);
  const Found far = segment (scene.render (small));
  ASSERT_EQ (far.persons.size (), 1u);
  EXPECT_TRUE (far.infos[0].too_far);
  Segmentation seg;
  seg.setInputCloud (scene.render (small));
  std::vector<pcl::PointIndices> persons;
  seg.segment (persons);
  ASSERT_EQ (seg.getTooFar ().size (), 1u);
  EXPECT_TRUE (seg.getTooFar ()[0]);
}

TEST (PersonSegmentation, PeopleWithoutAFloorInViewAreFound)
{
  // The background already removed (nothing but the people in the frame, no floor): one at
  // 2.5 m and one at 4.5 m, each found by the floor-free rule with all its pixels.
  Scene scene;
  scene.floor = false;
  scene.addPerson (-0.5, 2.5);
  scene.addPerson (0.8, 4.5);
  const DepthCamera cam;
  Segmentation seg;
  const Found found = segment (scene.render (cam), &seg);
  EXPECT_FALSE (seg.getFloorFound ());
  ASSERT_EQ (found.persons.size (), 2u);
  const bool near_first = found.infos[0].distance < found.infos[1].distance;
  const auto near = personMask (-0.5, 2.5, cam), far = personMask (0.8, 4.5, cam);
  for (int k = 0; k < 2; ++k)
  {
    double recall, precision;
    overlap (found.persons[k], (k == 0) == near_first ? near : far, recall, precision);
    EXPECT_GT (recall, 0.97) << "person " << k;
    EXPECT_GT (precision, 0.99) << "person " << k;
    EXPECT_FALSE (found.infos[k].on_floor);
  }
}

TEST (PersonSegmentation, PersonCutByTheLeftBorderKeepsItsVisibleParts)
{
  // At 3 m the image's left border lies 1.826 m left of the axis: a person 0.12 m right of it
  // has the left arm and half the body outside the frame and the left leg at the border.
  Scene scene;
  const double x = -319.5 / 525.0 * 3.0 + 0.12;
  scene.addPerson (x, 3.0);
  scene.addPerson (1.0, 3.5);  // and someone else in full view
  const DepthCamera cam;
  const Cloud::Ptr cloud = scene.render (cam);
  const Found found = segment (cloud);
  ASSERT_EQ (found.persons.size (), 2u);
  const int k = meanColumn (*cloud, found.persons[0]) < meanColumn (*cloud, found.persons[1]) ? 0 : 1;
  EXPECT_TRUE (found.infos[k].border & agex::PersonInfo::kLeft);
  double recall, precision;
  overlap (found.persons[k], personMask (x, 3.0, cam), recall, precision);
  EXPECT_GT (recall, 0.95);
  EXPECT_GT (precision, 0.99);
  // Both legs (0.2-0.8 m above the floor): the left one's visible strip at columns 0-12,
  // the right one round column 38.
  long left_leg = 0, right_leg = 0;
  for (const auto i : found.persons[k].indices)
  {
    const double height = 1.0 - (*cloud)[i].y;
    const int u = i % cam.width;
    if (height < 0.2 || height > 0.8)
      continue;
    left_leg += u <= 12;
    right_leg += u >= 28 && u <= 50;
  }
  EXPECT_GT (left_leg, 500);
  EXPECT_GT (right_leg, 1500);
}

TEST (PersonSegmentation, HeadAndShouldersCutByTheLowerBorderAreAPerson)
{
  // A camera 1.75 m high, 0.9 m from someone, no floor in view (background removed): the
  // image's lower border crosses the chest at about 1.34 m, so the head, the neck and the
  // tops of the shoulders show, less than a whole person's least area. A box of about that
  // size cut by the border (0.33 m wide, 0.32 m of it in view: upright enough for the
  // floor-free rule) is still no one: it is as wide on top as below.
  Scene scene;
  scene.floor = false;
  scene.camera_height = 1.75;
  scene.addPerson (0.0, 0.9);
  const DepthCamera cam;
  const Cloud::Ptr cloud = scene.render (cam);
  double area = 0.0;
  for (const auto &p : *cloud)
    if (std::isfinite (p.z))
      area += (p.z / cam.f) * (p.z / cam.f);  // the pixel's footprint facing the camera
  Segmentation seg;
  ASSERT_GT (area, seg.getHiddenPersonMinArea ());
  ASSERT_LT (area, seg.getMinArea ()) << "the fixture must show less than a whole person's least area";
  const Found found = segment (cloud, &seg);
  ASSERT_EQ (found.persons.size (), 1u);
  EXPECT_TRUE (found.infos[0].border & agex::PersonInfo::kBottom);
  EXPECT_FALSE (seg.getFloorFound ());

  Scene box_scene;
  box_scene.floor = false;
  box_scene.camera_height = 1.75;
  box_scene.addBox (-0.165, 0.165, 1.0, 1.66, 0.9, 1.1);
  const Found box = segment (box_scene.render (cam));
  EXPECT_TRUE (box.persons.empty ());
}

TEST (PersonSegmentation, FloorSeenOnlyFarAwayIsFound)
{
  // A person at 5 m in front of a wall at 6 m, the floor in view only from 4.5 m on (as in a
  // frame moved back from the camera, or a camera tilted up): three rows of cells of floor,
  // enough to find it; without it the person's feet join the floor and nobody is found.
  // A time-of-flight camera's noise (a third of a Kinect's at 5 m; with a Kinect's, noisy
  // cells of the wall and the person pass for level ones too).
  Scene scene;
  scene.noise = 0.0005;
  scene.addBox (-4.0, 4.0, 0.0, 2.6, 6.0, 6.1);
  scene.addPerson (0.3, 5.0);
  const DepthCamera cam;
  const Cloud::Ptr cloud = scene.render (cam);
  for (auto &p : *cloud)
    if (p.z < 4.5f && 1.f - p.y < 0.1f)
      p = agex_test::nanPoint ();
  Segmentation seg;
  const Found found = segment (cloud, &seg);
  EXPECT_TRUE (seg.getFloorFound ());
  // Where the person stands, the plane is the floor (its tilt and offset are less sure,
  // seen over 1.5 m of depth only).
  const Eigen::Vector4f plane = seg.getFloorPlane ();
  EXPECT_NEAR (plane.head<3> ().dot (Eigen::Vector3f (0.3f, 1.f, 5.f)) + plane[3], 0.0, 0.02) << plane.transpose ();
  ASSERT_EQ (found.persons.size (), 1u);
  EXPECT_TRUE (found.infos[0].on_floor);
  double recall, precision;
  overlap (found.persons[0], personMask (0.3, 5.0, cam), recall, precision);
  EXPECT_GT (recall, 0.95);
  EXPECT_GT (precision, 0.98);
}

TEST (PersonSegmentation, FeetJustAboveTheFloorStayWithThePerson)
{
  // The floor margin (4 cm) would cut the feet off at the floor: with setFloorContact the
  // shoe's pixels 1.5-3 cm above the floor are the person's, the floor beside them is not.
  for (const double z : {2.5, 4.0})
  {
    SCOPED_TRACE (z);
    Scene scene;
    scene.addPerson (0.2, z);
    const DepthCamera cam;
    const Cloud::Ptr cloud = scene.render (cam);
    Segmentation with_contact;
    with_contact.setFloorContact (true);
    const Found found = segment (cloud, &with_contact);
    ASSERT_EQ (found.persons.size (), 1u);
    // The person alone without noise: which pixels are its feet, how high.
    Scene alone;
    alone.floor = false;
    alone.noise = 0.0;
    alone.addPerson (0.2, z);
    const Cloud::Ptr exact = alone.render (cam);
    long low = 0, low_kept = 0, floor_taken = 0;
    for (std::size_t i = 0; i < cloud->size (); ++i)
    {
      const bool person = std::isfinite ((*exact)[i].z);
      const double height = 1.0 - (*exact)[i].y;
      if (person && height > 0.015 && height <= 0.03)
      {
        ++low;
        low_kept += found.labels[i].label == 0;
      }
      floor_taken += !person && found.labels[i].label == 0;
    }
    ASSERT_GT (low, 20);
    EXPECT_GT (low_kept, 0.8 * low) << low_kept << " of " << low;
    EXPECT_LT (floor_taken, 0.002 * found.persons[0].indices.size ());
  }
}

TEST (PersonSegmentation, SameResultAtEveryResolutionAndPointType)
{
  Scene scene;
  scene.addPerson (-0.5, 2.2);
  scene.addPerson (0.6, 4.0);
  scene.addChair (0.0, 3.0);
  for (const int width : {176, 320, 640, 1280})
  {
    SCOPED_TRACE (width);
    const DepthCamera cam = DepthCamera ().scaled (width);
    const Cloud::Ptr cloud = scene.render (cam);
    const Found found = segment (cloud);
    ASSERT_EQ (found.persons.size (), 2u);
    // The XYZRGBA and XYZI instantiations give the same persons.
    pcl::PointCloud<pcl::PointXYZRGBA>::Ptr rgba (new pcl::PointCloud<pcl::PointXYZRGBA>);
    pcl::copyPointCloud (*cloud, *rgba);
    agex::PersonSegmentation<pcl::PointXYZRGBA> seg_rgba;
    seg_rgba.setInputCloud (rgba);
    std::vector<pcl::PointIndices> persons_rgba;
    seg_rgba.segment (persons_rgba);
    ASSERT_EQ (persons_rgba.size (), 2u);
    EXPECT_EQ (persons_rgba[0].indices, found.persons[0].indices);
    pcl::PointCloud<pcl::PointXYZI>::Ptr xyzi (new pcl::PointCloud<pcl::PointXYZI>);
    pcl::copyPointCloud (*cloud, *xyzi);
    agex::PersonSegmentation<pcl::PointXYZI> seg_i;
    seg_i.setInputCloud (xyzi);
    std::vector<pcl::PointIndices> persons_i;
    seg_i.segment (persons_i);
    ASSERT_EQ (persons_i.size (), 2u);
    EXPECT_EQ (persons_i[1].indices, found.persons[1].indices);
  }
}

TEST (PersonSegmentation, GivenFloorAndIndicesAreHonoured)
{
  Scene scene;
  scene.addPerson (-0.5, 3.0);
  scene.addPerson (0.5, 3.0);
  const DepthCamera cam;
  const Cloud::Ptr cloud = scene.render (cam);

  // The floor as FloorRemoval reports it: n.p + d = height, n pointing up (-y).
  Segmentation seg;
  seg.setFloorPlane (Eigen::Vector4f (0.f, -2.f, 0.f, 2.f));  // any scale
  Found found = segment (cloud, &seg);
  EXPECT_TRUE (seg.getFloorFound ());
  EXPECT_TRUE (seg.getFloorPlane ().isApprox (Eigen::Vector4f (0.f, -1.f, 0.f, 1.f)));
  EXPECT_EQ (found.persons.size (), 2u);

  // The same plane written the other way round.
  seg.setFloorPlane (Eigen::Vector4f (0.f, 1.f, 0.f, -1.f));
  found = segment (cloud, &seg);
  EXPECT_TRUE (seg.getFloorPlane ().isApprox (Eigen::Vector4f (0.f, -1.f, 0.f, 1.f)));
  EXPECT_EQ (found.persons.size (), 2u);

  // The floor's points already removed: found only when the plane is given.
  Cloud::Ptr no_floor (new Cloud (*cloud));
  for (auto &p : *no_floor)
    if (1.f - p.y < 0.04f)
      p = agex_test::nanPoint ();
  Segmentation alone;
  found = segment (no_floor, &alone);
  EXPECT_FALSE (alone.getFloorFound ());
  seg.setFloorPlane (Eigen::Vector4f (0.f, -1.f, 0.f, 1.f));
  found = segment (no_floor, &seg);
  ASSERT_EQ (found.persons.size (), 2u);
  EXPECT_TRUE (found.infos[0].on_floor);

  // A floor 0.9 m too high leaves nobody tall enough.
  seg.setFloorPlane (Eigen::Vector4f (0.f, -1.f, 0.f, 0.1f));
  found = segment (cloud, &seg);
  EXPECT_EQ (found.persons.size (), 0u);

  // Only the left half of the image: only the left person.
  seg.resetFloorPlane ();
  pcl::IndicesPtr left (new pcl::Indices);
  for (int i = 0; i < static_cast<int> (cloud->size ()); ++i)
    if (i % cam.width < cam.width / 2)
      left->push_back (i);
  seg.setIndices (left);
  found = segment (cloud, &seg);
  ASSERT_EQ (found.persons.size (), 1u);
  EXPECT_LT (found.infos[0].ground.x (), 0.f);
  for (const auto i : found.persons[0].indices)
    ASSERT_LT (i % cam.width, cam.width / 2);
}

TEST (PersonSegmentation, PersonOfMeshes)
{
  Scene scene;
  scene.addPerson (-0.5, 3.0);
  scene.addPerson (0.5, 3.0);
  scene.addChair (1.5, 3.0);
  const Cloud::Ptr cloud = scene.render (DepthCamera ());
  const Found found = segment (cloud);
  ASSERT_EQ (found.persons.size (), 2u);
  agex::SurfaceSegmentation<pcl::PointXYZ> meshes;
  meshes.setInputCloud (cloud);
  pcl::IndicesPtr above (new pcl::Indices);  // the floor removed, as in the depth pipeline
  for (int i = 0; i < static_cast<int> (cloud->size ()); ++i)
    if (1.f - (*cloud)[i].y > 0.05f)
      above->push_back (i);
  meshes.setIndices (above);
  meshes.setDeltaConnected (0.05f);
  meshes.setMinMeshSize (500);
  std::vector<pcl::PointIndices> surfaces;
  meshes.segment (surfaces);
  const std::vector<int> person = agex::personOfMeshes (found.labels, surfaces);
  ASSERT_EQ (person.size (), surfaces.size ());
  std::set<int> seen (person.begin (), person.end ());
  EXPECT_TRUE (seen.count (0) && seen.count (1));
  EXPECT_TRUE (seen.count (-1));  // the chair
  for (std::size_t m = 0; m < surfaces.size (); ++m)
    if (person[m] >= 0)
    {
      const auto label = static_cast<std::uint32_t> (person[m]);
      const auto on = std::count_if (surfaces[m].indices.begin (), surfaces[m].indices.end (),
                                     [&] (int i) { return found.labels[i].label == label; });
      EXPECT_GT (2 * on, static_cast<long> (surfaces[m].indices.size ()));
    }
}

// ---------------------------------------------------------------------------------------
// Misuse and degenerate frames

TEST (PersonSegmentation, EmptyAllNaNAndUnorganizedInputGiveNoPersons)
{
  agex_test::QuietPcl quiet;
  Segmentation seg;
  std::vector<pcl::PointIndices> persons (3);
  Cloud::Ptr empty (new Cloud);
  seg.setInputCloud (empty);
  seg.segment (persons);
  EXPECT_TRUE (persons.empty ());

  seg.setInputCloud (agex_test::nanCloud (64, 48));
  persons.resize (2);
  seg.segment (persons);
  EXPECT_TRUE (persons.empty ());
  EXPECT_FALSE (seg.getFloorFound ());

  Scene scene;
  scene.addPerson (0.0, 3.0);
  Cloud::Ptr flat (new Cloud (*scene.render (DepthCamera ())));
  flat->width = static_cast<std::uint32_t> (flat->size ());
  flat->height = 1;
  seg.setInputCloud (flat);
  seg.segment (persons);
  EXPECT_TRUE (persons.empty ());
  EXPECT_TRUE (seg.getPersons ().empty ());
}

TEST (PersonSegmentation, InvalidSettingsGiveNoPersons)
{
  agex_test::QuietPcl quiet;
  Scene scene;
  scene.addPerson (0.0, 3.0);
  const Cloud::Ptr cloud = scene.render (DepthCamera ());
  auto count = [&] (const std::function<void (Segmentation &)> &set) {
    Segmentation seg;
    set (seg);
    return segment (cloud, &seg).persons.size ();
  };
  EXPECT_EQ (count ([] (Segmentation &) {}), 1u);
  const float nan = std::numeric_limits<float>::quiet_NaN ();
  EXPECT_EQ (count ([] (Segmentation &s) { s.setHeightLimits (2.f, 1.f); }), 0u);
  EXPECT_EQ (count ([&] (Segmentation &s) { s.setMaxWidth (nan); }), 0u);
  EXPECT_EQ (count ([] (Segmentation &s) { s.setUpAxis (Eigen::Vector3f::Zero ()); }), 0u);
  EXPECT_EQ (count ([] (Segmentation &s) { s.setCoarseStep (-1); }), 0u);
  EXPECT_EQ (count ([] (Segmentation &s) { s.setFloorMaxTilt (90.f); }), 0u);
  EXPECT_EQ (count ([] (Segmentation &s) { s.setFallbackLimits (0.3f, 1.5f); }), 0u);
  EXPECT_EQ (count ([] (Segmentation &s) { s.setSplitLimits (0.3f, 0.15f, 0.f); }), 0u);
  EXPECT_EQ (count ([&] (Segmentation &s) { s.setFloorPlane (Eigen::Vector4f (nan, -1.f, 0.f, 1.f)); }), 0u);
  EXPECT_EQ (count ([] (Segmentation &s) { s.setFloorPlane (Eigen::Vector4f (0.f, 0.f, 0.f, 1.f)); }), 0u);
  // Out-of-range indices are ignored, not read.
  EXPECT_EQ (count ([] (Segmentation &s) {
               pcl::IndicesPtr odd (new pcl::Indices{-5, 1 << 30});
               s.setIndices (odd);
             }),
             0u);
}

TEST (PersonSegmentation, AbsurdlyLargeOrSmallFramesGiveNoPersonsAndNoCrash)
{
  // Each of these once crashed in the bins of a cluster (a coordinate difference over the bin
  // size overflowed the int index): metric sizes that do not fit the frame give no persons.
  agex_test::QuietPcl quiet;
  // 16x12 points 1e8 m apart at 2 m depth (agex_keypoints tiny.pcd).
  Cloud::Ptr tiny (new Cloud (16, 12));
  for (int v = 0; v < 12; ++v)
    for (int u = 0; u < 16; ++u)
      (*tiny) (u, v).getVector3fMap () = Eigen::Vector3f ((u - 8) * 1e8f, (v - 6) * 1e8f, 2.f);
  EXPECT_TRUE (segment (tiny).persons.empty ());

  Scene scene;
  scene.addPerson (0.0, 3.0);
  const Cloud::Ptr cloud = scene.render (DepthCamera ());
  ASSERT_EQ (segment (cloud).persons.size (), 1u);
  // Focal lengths of 1e-6 and 1e-30 px (--fx 1e-6 --fy 1e-6), and 1e30: refused, not used.
  for (const float f : {1e-6f, 1e-30f, 1e30f})
  {
    Segmentation seg;
    seg.setFocalLength (f, f);
    EXPECT_TRUE (segment (cloud, &seg).persons.empty ()) << f;
  }
  // A head distance beyond any profile: the peak window is the profile, not an overflowed int.
  Segmentation wide;
  wide.setSplitLimits (3e38f, 0.15f);
  EXPECT_EQ (segment (cloud, &wide).persons.size (), 1u);
  // The person's x and y scaled by 1e7 (the Bonn frame so scaled crashed): the fitted focal
  // length is far below a pixel.
  Cloud::Ptr stretched (new Cloud (*cloud));
  for (auto &p : *stretched)
    p.x *= 1e7f, p.y *= 1e7f;
  Segmentation estimated;
  EXPECT_TRUE (segment (stretched, &estimated).persons.empty ());
  EXPECT_LT (estimated.getUsedFocalLengthX (), 1e-3f);
  // Depths of 3.4e38 m (a float depth image of FLT_MAX) with the camera's focal length: finite
  // coordinates whose differences are infinite.
  Cloud::Ptr far (new Cloud (*cloud));
  for (auto &p : *far)
    if (std::isfinite (p.z))
      p.getVector3fMap () *= 3.4e38f / std::max (p.z, 1.f);
  Segmentation given;
  given.setFocalLength (525.f, 525.f);
  EXPECT_TRUE (segment (far, &given).persons.empty ());
}

// ---------------------------------------------------------------------------------------
// Real frames

namespace
{
const char *const kSkeltrackFrames[] = {"depth-data-1028894671", "depth-data-1045879925", "depth-data-1058893191",
                                        "depth-data-1070905432", "depth-data-1166565565", "depth-data-1399145206"};
}

TEST (PersonSegmentationReal, SkeltrackUpperBodiesWithoutAFloor)
{
  // Six frames of close upper bodies (0.8-2 m), the background zeroed. Looked at by hand:
  // 1399145206 shows two people, a near one (1.3 m, a hand raised at 0.9 m) and one behind
  // (1.9 m, head hidden by that hand); the other five show one person.
  for (const char *name : kSkeltrackFrames)
  {
    const std::string path = agex_test::sharedData (std::string ("kinect/skeltrack/") + name + ".u16");
    AGEX_REQUIRE_SHARED_FILE (path, "Skeltrack's depth frames (../shared/data/kinect/skeltrack)");
    SCOPED_TRACE (name);
    const agex::Frame frame = agex::loadFrame (path);
    Segmentation seg;
    const Found found = segment (frame.cloud, &seg);
    EXPECT_FALSE (seg.getFloorFound ());  // the lower edge of a torso is no floor
    const bool two = std::string (name) == "depth-data-1399145206";
    ASSERT_EQ (found.persons.size (), two ? 2u : 1u);
    std::size_t finite = 0, found_points = 0;
    for (const auto &p : *frame.cloud)
      finite += std::isfinite (p.z);
    for (std::size_t k = 0; k < found.persons.size (); ++k)
    {
      found_points += found.persons[k].indices.size ();
      EXPECT_FALSE (found.infos[k].on_floor);
      EXPECT_FALSE (found.infos[k].too_far);
      EXPECT_TRUE (found.infos[k].border & agex::PersonInfo::kBottom);  // cut off at the waist
    }
    // Nearly everything in view is someone (hands held out in front included).
    EXPECT_GT (found_points, 0.97 * finite);
    if (two)
    {
      EXPECT_NEAR (found.infos[0].distance, 1.3, 0.1);
      EXPECT_NEAR (found.infos[1].distance, 1.9, 0.1);
    }
  }
}

TEST (PersonSegmentationReal, FivePeopleInPclsFrame)
{
  // PCL's five_people.pcd: five people walking away down a corridor, all of them within
  // 1.8-2.8 m (the 9.8 m is the corridor's end). Looked at by hand, left to right, their
  // pixel columns: 21-151, 144-244, 276-375, 373-470 and 456-605; the two in the middle
  // right touch and come as one cluster that is cut between their heads.
  const std::string path = agex_test::sharedData ("kinect/five_people.pcd");
  AGEX_REQUIRE_SHARED_FILE (path, "PCL's five_people.pcd (../shared/data/kinect)");
  const agex::Frame frame = agex::loadFrame (path);
  Segmentation seg;
  const Found found = segment (frame.cloud, &seg);
  EXPECT_TRUE (seg.getFloorFound ());
  ASSERT_EQ (found.persons.size (), 5u);
  const double columns[5][2] = {{21, 151}, {144, 244}, {276, 375}, {373, 470}, {456, 605}};
  std::vector<int> matched (5, 0);
  for (std::size_t k = 0; k < 5; ++k)
  {
    const double centre = meanColumn (*frame.cloud, found.persons[k]);
    for (int c = 0; c < 5; ++c)
      if (centre > columns[c][0] + 20 && centre < columns[c][1] - 20)
        ++matched[c];
    const agex::PersonInfo &info = found.infos[k];
    EXPECT_GT (info.distance, 1.7f);
    EXPECT_LT (info.distance, 2.9f);
    EXPECT_GT (info.top, 1.6f);
    EXPECT_LT (info.top, 1.9f);
    EXPECT_GT (info.points, 15000);
    EXPECT_FALSE (info.too_far);
  }
  EXPECT_EQ (matched, std::vector<int> (5, 1));
}

namespace
{
/** Every finite point moved by (dx, 0, dz), projected with the Kinect intrinsics and
  * z-buffered into a frame of the same size (each point over the pixels its own pixel covers
  * at the new depth, nearest wins); tag goes along with the points. */
Cloud::Ptr
movedFrame (const Cloud &in, const std::vector<unsigned char> &tag, float dx, float dz, std::vector<unsigned char> &moved_tag)
{
  const DepthCamera cam;
  const int w = static_cast<int> (in.width), h = static_cast<int> (in.height);
  Cloud::Ptr out = agex_test::nanCloud (w, h);
  moved_tag.assign (in.size (), 0);
  for (std::size_t i = 0; i < in.size (); ++i)
  {
    const pcl::PointXYZ &p = in[i];
    if (!std::isfinite (p.z))
      continue;
    const float x = p.x + dx, z = p.z + dz;
    const int s = std::max (1, static_cast<int> (std::ceil (p.z / z - 1e-3f)));
    const auto u0 = static_cast<int> (std::lround (cam.f * x / z + cam.cx - 0.5 * (s - 1)));
    const auto v0 = static_cast<int> (std::lround (cam.f * p.y / z + cam.cy - 0.5 * (s - 1)));
    for (int v = std::max (0, v0); v < std::min (h, v0 + s); ++v)
      for (int u = std::max (0, u0); u < std::min (w, u0 + s); ++u)
      {
        pcl::PointXYZ &q = (*out) (u, v);
        if (std::isfinite (q.z) && q.z <= z)
          continue;
        q = pcl::PointXYZ (static_cast<float> ((u - cam.cx) * z / cam.f), static_cast<float> ((v - cam.cy) * z / cam.f), z);
        moved_tag[v * w + u] = tag[i];
      }
  }
  return out;
}
}  // namespace

TEST (PersonSegmentationReal, BonnPersonMovedBackIsFound)
{
  // Bonn keyframes (one with both hands on the head) with every point moved 1-2 m back and
  // up to 0.6 m sideways, the person at 3.3-4.3 m: still exactly one person, with the pixels
  // of the person at its own distance that are still in view (the floor is in view only from
  // 3.2-4.2 m on; the crown of the hands on the head must not take in the elbows), and the
  // feet.
  const std::string labels_path = agex_test::sharedData ("bonn/labels.csv");
  AGEX_REQUIRE_BONN (labels_path);
  const std::vector<agex::BonnLabel> labels = agex::readBonnLabels (labels_path);
  const char *const frames[][2] = {{"5", "037"}, {"7", "022"}, {"8", "040"}};
  const float moves[][2] = {{1.f, 0.f}, {1.5f, 0.f}, {2.f, 0.f}, {2.f, -0.6f}, {2.f, 0.6f}};
  int feet = 0, feet_found = 0;
  for (const auto &id : frames)
  {
    const std::string path = agex_test::sharedData (std::string ("bonn/depth/") + id[0] + "/" + id[1] + ".png");
    AGEX_REQUIRE_BONN (path);
    const agex::Frame frame = agex::loadFrame (path);
    const Found native = segment (frame.cloud);
    ASSERT_EQ (native.persons.size (), 1u);
    std::vector<unsigned char> person (frame.cloud->size (), 0);
    for (const auto i : native.persons[0].indices)
      person[i] = 1;
    std::vector<Eigen::Vector3f> toes;
    for (const auto &l : labels)
    {
      Eigen::Vector3f p;
      if (l.sequence == id[0] && l.frame == id[1] && l.part == agex::BodyPart::Foot &&
          agex::liftPixelToSurface (*frame.cloud, l.tip_px.x (), l.tip_px.y (), 6, 0.05f, p))
        toes.push_back (p);
    }
    for (const auto &m : moves)
    {
      SCOPED_TRACE (std::string (id[0]) + "_" + id[1] + " moved by " + std::to_string (m[0]) + ", " +
                    std::to_string (m[1]));
      std::vector<unsigned char> carried;
      const Cloud::Ptr moved = movedFrame (*frame.cloud, person, m[1], m[0], carried);
      const Found found = segment (moved);
      ASSERT_EQ (found.persons.size (), 1u);
      EXPECT_NEAR (found.infos[0].distance, native.infos[0].distance + m[0], 0.15);
      const auto in_view = std::count (carried.begin (), carried.end (), 1);
      const auto kept = std::count_if (found.persons[0].indices.begin (), found.persons[0].indices.end (),
                                       [&] (int i) { return carried[i] != 0; });
      EXPECT_GT (kept, 0.95 * in_view);
      EXPECT_GT (kept, 0.98 * found.persons[0].indices.size ());
      // A person pixel within 5 cm of each labelled toe.
      for (const auto &toe : toes)
      {
        const Eigen::Vector3f q = toe + Eigen::Vector3f (m[1], 0.f, m[0]);
        ++feet;
        feet_found += std::any_of (found.persons[0].indices.begin (), found.persons[0].indices.end (),
                                   [&] (int i) { return ((*moved)[i].getVector3fMap () - q).norm () < 0.05f; });
      }
    }
  }
  EXPECT_EQ (feet, 30);
  EXPECT_EQ (feet_found, feet);
}

TEST (PersonSegmentationReal, BonnPersonAtBothViews)
{
  // One person in a cluttered office (shelves, a chair, floor clutter): exactly one person,
  // at about 2.3 m, with the labelled tips on it.
  const std::string labels_path = agex_test::sharedData ("bonn/labels.csv");
  AGEX_REQUIRE_BONN (labels_path);
  const std::vector<agex::BonnLabel> labels = agex::readBonnLabels (labels_path);
  // A keyframe of every sequence; in 5_025 both hands are on the head.
  const char *const frames[][2] = {{"1", "002"}, {"2", "005"}, {"3", "030"}, {"4", "009"},
                                   {"5", "025"}, {"6", "031"}, {"7", "022"}, {"8", "040"}};
  int tips = 0, on_person = 0;
  for (const auto &id : frames)
  {
    const std::string path = agex_test::sharedData (std::string ("bonn/depth/") + id[0] + "/" + id[1] + ".png");
    AGEX_REQUIRE_BONN (path);
    const agex::Frame frame = agex::loadFrame (path);
    Cloud::Ptr portrait (new Cloud);
    agex::applyView (*frame.cloud, agex::bonnPortraitView (), *portrait);
    for (const Cloud::Ptr &cloud : {frame.cloud, portrait})
    {
      SCOPED_TRACE (std::string (id[0]) + "_" + id[1] + " at " + std::to_string (cloud->width));
      const Found found = segment (cloud);
      ASSERT_EQ (found.persons.size (), 1u);
      EXPECT_NEAR (found.infos[0].distance, 2.3, 0.15);
      EXPECT_TRUE (found.infos[0].on_floor);
      if (cloud != frame.cloud)
        continue;
      for (const auto &l : labels)
      {
        if (l.sequence != id[0] || l.frame != id[1] || !l.keyframe)
          continue;
        // Tips with depth within 3 pixels (some lie on hair or in a hole of the data).
        bool data = false, near = false;
        const int u0 = static_cast<int> (std::lround (l.tip_px.x ()));
        const int v0 = static_cast<int> (std::lround (l.tip_px.y ()));
        for (int v = v0 - 3; v <= v0 + 3; ++v)
          for (int u = u0 - 3; u <= u0 + 3; ++u)
            if (u >= 0 && u < 640 && v >= 0 && v < 480)
            {
              data = data || std::isfinite ((*cloud) (u, v).z);
              near = near || found.labels[v * 640 + u].label == 0;
            }
        tips += data;
        on_person += data && near;
      }
    }
  }
  EXPECT_GT (tips, 30);
  EXPECT_EQ (on_person, tips);
}
