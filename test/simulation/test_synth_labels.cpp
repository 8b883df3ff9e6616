// Synthetic per-pixel part and person labels: each label is that of the surface the
// depth pixel shows (checked by casting the pixel's ray again, brute force, against
// every primitive), hidden parts are never labelled, hand pixels lie on the hand's
// capsule or mesh triangles, and the label images round-trip through a dataset.

#include "test_support.h"

#include <agex/io/dataset.h>
#include <agex/simulation/human_mesh.h>
#include <agex/simulation/synth_mesh.h>
#include <agex/simulation/synthetic_scene.h>

#include <map>
#include <memory>
#include <set>

namespace
{
using namespace agex_test;

#define AGEX_REQUIRE_MOCAP(path) AGEX_REQUIRE_SHARED_FILE (path, "the CMU motion capture (../shared/data/mocap)")
#define AGEX_REQUIRE_MAKEHUMAN()                                                        \
  AGEX_REQUIRE_SHARED_FILE (sharedData ("makehuman/default_weights.mhw"),                 \
                            "the MakeHuman body mesh (../shared/data/makehuman)")

/** Generators of the tests below (the mesh and its floor placement take ~1 s). */
const agex::SynthGenerator &
labelGenerator (agex::SynthSensor sensor, bool mesh)
{
  static std::map<std::pair<int, bool>, std::unique_ptr<agex::SynthGenerator>> cache;
  auto &g = cache[{static_cast<int> (sensor), mesh}];
  if (!g)
  {
    agex::SynthOptions options;
    options.motion_files = {sharedData ("mocap/cmu_131_01.bvh"), sharedData ("mocap/cmu_05_06.bvh")};
    options.sensor = sensor;
    options.seed = 23;
    if (mesh)
      options.body_mesh = sharedData ("makehuman");
    g = std::make_unique<agex::SynthGenerator> (options);
  }
  return *g;
}

/** The nearest hit of a ray among all of a scene's primitives, by brute force (no tiles). */
struct RayHit
{
  int primitive = -1, triangle = -1;
  double t = -1.0;
};

RayHit
castRay (const agex::SynthScene &scene, const Eigen::Vector3d &o, const Eigen::Vector3d &d)
{
  RayHit best;
  for (std::size_t i = 0; i < scene.primitives.size (); ++i)
  {
    const agex::SynthPrimitive &p = scene.primitives[i];
    int triangle = -1;
    const double t = p.intersect (o, d, 1e-6, nullptr, &triangle);
    if (t > 0 && (best.t < 0 || t < best.t))
      best = RayHit{static_cast<int> (i), triangle, t};
  }
  return best;
}

/** The label a ray's nearest surface has: its part (0 for the room) and person. */
std::pair<int, int>
expectedLabel (const agex::SynthScene &scene, const RayHit &hit)
{
  if (hit.t < 0)
    return {0, 0};
  const agex::SynthPrimitive &p = scene.primitives[static_cast<std::size_t> (hit.primitive)];
  const int part = static_cast<int> (p.partAt (hit.triangle));
  return {part, part ? p.person : 0};
}

Eigen::Vector3d
pixelRay (const agex::CameraIntrinsics &k, double u, double v)
{
  return Eigen::Vector3d ((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0).normalized ();
}

bool
isHand (int part)
{
  return part == static_cast<int> (agex::SynthPart::LeftHand) || part == static_cast<int> (agex::SynthPart::RightHand);
}

/** The surfaces of a scene labelled with one part: its capsules and ellipsoids, and
  * the triangles of that part of every mesh (each as a mesh of its own). */
class PartSurface
{
public:
  PartSurface (const agex::SynthScene &scene, agex::SynthPart part)
  {
    for (const auto &prim : scene.primitives)
    {
      if (prim.object != agex::SynthObject::Person)
        continue;
      if (prim.shape != agex::SynthPrimitive::Shape::Mesh)
      {
        if (prim.partAt (-1) == part)
          shapes_.push_back (prim);
        continue;
      }
      std::vector<Eigen::Vector3i> own;
      for (std::size_t t = 0; t < prim.mesh->triangles ().size (); ++t)
        if (prim.partAt (static_cast<int> (t)) == part)
          own.push_back (prim.mesh->triangles ()[t]);
      if (!own.empty ())
      {
        agex::SynthPrimitive piece = prim;
        piece.mesh = std::make_shared<const agex::SynthMesh> (prim.mesh->vertices (), own);
        shapes_.push_back (piece);
      }
    }
  }

  /** Distance of p to the part's surface (+inf if the scene has no such part). */
  double distance (const Eigen::Vector3d &p) const
  {
    double best = std::numeric_limits<double>::infinity ();
    for (const auto &shape : shapes_)
      best = std::min (best, std::abs (shape.distance (p)));
    return best;
  }

private:
  std::vector<agex::SynthPrimitive> shapes_;
};

class SynthPartLabelSensors : public ::testing::TestWithParam<std::tuple<agex::SynthSensor, bool>>
{
protected:
  agex::SynthSensor sensorKind () const { return std::get<0> (GetParam ()); }
  bool mesh () const { return std::get<1> (GetParam ()); }
};

// Each pixel's label is that of the nearest surface along its ray (so hidden parts are
// never labelled), every labelled pixel has a depth and every body pixel with a depth
// has a label. Kinect and bonn measure along the pixel-centre ray: exact. sr4000 blends
// 3x3 samples: pixels whose neighbourhood sees one primitive take the centre's label;
// the others (silhouettes, part edges) the label of a sample whose surface lies at the
// measured depth (within the noise).
TEST_P (SynthPartLabelSensors, LabelsAreThoseOfTheSurfaceTheDepthShows)
{
  AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_131_01.bvh"));
  AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_05_06.bvh"));
  if (mesh ())
    AGEX_REQUIRE_MAKEHUMAN ();
  const agex::SynthGenerator &gen = labelGenerator (sensorKind (), mesh ());
  const agex::SensorModel &sensor = gen.sensor ();
  const bool tof = sensorKind () == agex::SynthSensor::Sr4000, bonn = sensorKind () == agex::SynthSensor::Bonn;
  const agex::SensorModel kinect = agex::sensorModel (agex::SynthSensor::Kinect);
  const agex::FrameView view = agex::bonnPortraitView ();
  const int w = sensor.width, h = sensor.height;
  const int frames = sensorKind () == agex::SynthSensor::Kinect ? 2 : 5;
  std::size_t labelled = 0, body_pixels = 0, mixed_checked = 0;
  std::set<int> parts_seen;
  for (int f = 0; f < frames; ++f)
  {
    const agex::SynthFrame frame = gen.render (static_cast<std::uint64_t> (f));
    const std::size_t n = static_cast<std::size_t> (w) * h;
    ASSERT_EQ (frame.part_label.size (), n);
    ASSERT_EQ (frame.person_label.size (), n);
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u)
      {
        const std::size_t i = static_cast<std::size_t> (v) * w + u;
        const std::string where = "frame " + std::to_string (f) + " pixel (" + std::to_string (u) + ", " +
                                  std::to_string (v) + ")";
        const int part = frame.part_label[i], person = frame.person_label[i];
        const pcl::PointXYZ &p = frame.cloud.points[i];
        ASSERT_EQ (part != 0, person != 0) << where;
        if (!isFinite (p))
        {
          ASSERT_EQ (part, 0) << where << ": labelled without a depth";
          continue;
        }
        labelled += part != 0;
        parts_seen.insert (part);
        bool uniform = true;
        if (tof)
          for (int dv = -1; dv <= 1; ++dv)
            for (int du = -1; du <= 1; ++du)
            {
              const int uu = std::clamp (u + du, 0, w - 1), vv = std::clamp (v + dv, 0, h - 1);
              uniform = uniform && frame.primitive[static_cast<std::size_t> (vv) * w + uu] == frame.primitive[i];
            }
        if (uniform)
        {
          // The ray the depth was measured along: the pixel's, or for bonn its source pixel's.
          Eigen::Vector3d d = pixelRay (sensor.intrinsics, u, v);
          if (bonn)
          {
            const cv::Point s = view.sourcePixel (u, v);
            d = pixelRay (kinect.intrinsics, s.x, s.y);
          }
          const auto expected = expectedLabel (frame.scene, castRay (frame.scene, Eigen::Vector3d::Zero (), d));
          body_pixels += expected.first != 0;
          ASSERT_EQ (part, expected.first) << where;
          ASSERT_EQ (person, expected.second) << where;
          continue;
        }
        if (part == 0)
          continue;
        // A mixed sr4000 pixel: the sample whose range is nearest to the blended range
        // (before noise) sees the labelled part, within 1 cm + 1% of that range.
        ++mixed_checked;
        const double range = frame.clean_z[i] / pixelRay (sensor.intrinsics, u, v).z ();
        double gap = std::numeric_limits<double>::infinity ();
        int nearest = -1;
        for (int sy = 0; sy < 3; ++sy)
          for (int sx = 0; sx < 3; ++sx)
          {
            const Eigen::Vector3d d = pixelRay (sensor.intrinsics, u + (sx - 1) / 3.0, v + (sy - 1) / 3.0);
            const RayHit hit = castRay (frame.scene, Eigen::Vector3d::Zero (), d);
            if (hit.t > 0 && std::abs (hit.t - range) < gap)
            {
              gap = std::abs (hit.t - range);
              nearest = expectedLabel (frame.scene, hit).first;
            }
          }
        ASSERT_LE (gap, 0.01 + 0.01 * range) << where;
        ASSERT_EQ (nearest, part) << where;
      }
  }
  EXPECT_GT (labelled, static_cast<std::size_t> (w) * h * frames / 40) << "the person is labelled";
  EXPECT_GT (body_pixels, labelled / 2);
  if (tof)
  {
    EXPECT_GT (mixed_checked, 0u);
  }
  // Most parts show up over a few frames (heads and feet may leave a close frame).
  EXPECT_GE (parts_seen.size (), 12u);
  EXPECT_EQ (parts_seen.count (static_cast<int> (agex::SynthPart::Unknown)), 0u) << "every body primitive has a part";
}

INSTANTIATE_TEST_SUITE_P (Synth, SynthPartLabelSensors,
                          ::testing::Combine (::testing::Values (agex::SynthSensor::Sr4000, agex::SynthSensor::Kinect,
                                                                 agex::SynthSensor::Bonn),
                                              ::testing::Bool ()),
                          [] (const ::testing::TestParamInfo<std::tuple<agex::SynthSensor, bool>> &info) {
                            return std::string (agex::synthSensorName (std::get<0> (info.param))) +
                                   (std::get<1> (info.param) ? "_mesh" : "_capsules");
                          });

/** The sensors whose points lie on their pixels' rays (not bonn: its view moves them). */
class SynthHandPixels : public SynthPartLabelSensors
{
};

// Hand pixels lie on the hand: the surface point of a kinect pixel's centre ray exactly
// (its noise-free depth), the measured point within the sensor's noise.
TEST_P (SynthHandPixels, LieOnTheHand)
{
  AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_131_01.bvh"));
  AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_05_06.bvh"));
  if (mesh ())
    AGEX_REQUIRE_MAKEHUMAN ();
  const agex::SynthGenerator &gen = labelGenerator (sensorKind (), mesh ());
  const agex::SensorModel &sensor = gen.sensor ();
  const bool tof = sensorKind () == agex::SynthSensor::Sr4000;
  std::size_t hand_pixels = 0;
  for (int f = 0; f < (tof ? 12 : 4); ++f)
  {
    const agex::SynthFrame frame = gen.render (static_cast<std::uint64_t> (f));
    const PartSurface left (frame.scene, agex::SynthPart::LeftHand), right (frame.scene, agex::SynthPart::RightHand);
    for (int v = 0; v < sensor.height; ++v)
      for (int u = 0; u < sensor.width; ++u)
      {
        const std::size_t i = static_cast<std::size_t> (v) * sensor.width + u;
        if (!isHand (frame.part_label[i]))
          continue;
        ++hand_pixels;
        const auto part = static_cast<agex::SynthPart> (frame.part_label[i]);
        const pcl::PointXYZ &p = frame.cloud.points[i];
        const Eigen::Vector3d measured (p.x, p.y, p.z);
        const std::string where = "frame " + std::to_string (f) + " pixel (" + std::to_string (u) + ", " +
                                  std::to_string (v) + ") " + agex::synthPartName (part);
        const PartSurface &hand = part == agex::SynthPart::LeftHand ? left : right;
        if (!tof)
        {
          const Eigen::Vector3d d = pixelRay (sensor.intrinsics, u, v);
          const Eigen::Vector3d surface = d * (frame.ideal_z[i] / d.z ());
          ASSERT_LT (hand.distance (surface), 1e-4) << where;
          // Disparity steps of z^2 / 348 and noise of about half a step.
          ASSERT_LT (hand.distance (measured), 0.005 + p.z * p.z / 348.0 * 2.5) << where;
        }
        else
        {
          // The blended range: on the hand up to the rule's 1 cm + 1%, and a sample's
          // offset from the centre ray (a third of a pixel).
          const Eigen::Vector3d d = pixelRay (sensor.intrinsics, u, v);
          const Eigen::Vector3d blended = d * (frame.clean_z[i] / d.z ());
          ASSERT_LT (hand.distance (blended), 0.01 + 0.01 * blended.norm () + 0.6 * p.z / sensor.intrinsics.fx)
              << where;
          // The measured point: and the noise, at most 5 cm (SensorModel::tof_sigma_max) times 3.
          ASSERT_LT (hand.distance (measured), 0.02 + 0.01 * p.z + 0.15) << where;
        }
      }
  }
  EXPECT_GT (hand_pixels, 20u);
}

INSTANTIATE_TEST_SUITE_P (Synth, SynthHandPixels,
                          ::testing::Combine (::testing::Values (agex::SynthSensor::Sr4000, agex::SynthSensor::Kinect),
                                              ::testing::Bool ()),
                          [] (const ::testing::TestParamInfo<std::tuple<agex::SynthSensor, bool>> &info) {
                            return std::string (agex::synthSensorName (std::get<0> (info.param))) +
                                   (std::get<1> (info.param) ? "_mesh" : "_capsules");
                          });

/** A hand-built scene: a torso, a hand behind it or in front of it, another hand beside
  * it, a wall behind. */
agex::SynthScene
handAndTorso (double left_hand_z)
{
  agex::SynthScene scene;
  auto person = [&] (agex::SynthPrimitive p, agex::SynthPart part) {
    p.part = part;
    scene.primitives.push_back (p);
  };
  person (agex::SynthPrimitive::ellipsoid ({0, 0, 2.5}, Eigen::Vector3d (0.2, 0.3, 0.12).asDiagonal (),
                                           agex::SynthObject::Person),
          agex::SynthPart::Torso);
  person (agex::SynthPrimitive::capsule ({-0.05, 0.0, left_hand_z}, {0.05, 0.0, left_hand_z}, 0.04,
                                         agex::SynthObject::Person),
          agex::SynthPart::LeftHand);
  person (agex::SynthPrimitive::capsule ({0.35, 0.0, 2.5}, {0.45, 0.0, 2.5}, 0.04, agex::SynthObject::Person),
          agex::SynthPart::RightHand);
  scene.primitives.push_back (agex::SynthPrimitive::plane ({0, 0, -1}, -4.0, agex::SynthObject::Wall));
  return scene;
}

TEST (SynthPartLabels, AHandBehindTheTorsoIsUnlabelled)
{
  for (const agex::SynthSensor kind : {agex::SynthSensor::Sr4000, agex::SynthSensor::Kinect})
  {
    const agex::SensorModel sensor = agex::sensorModel (kind);
    auto count = [&] (double left_hand_z) {
      agex::SynthRng rng (4);
      agex::SynthFrame frame;
      agex::renderScene (handAndTorso (left_hand_z), sensor, rng, frame);
      std::map<int, int> pixels;
      for (const auto label : frame.part_label)
        ++pixels[label];
      return pixels;
    };
    const std::string name = agex::synthSensorName (kind);
    // Behind the torso (2.8 m, the torso's back at 2.62 m): hidden, so never labelled.
    auto behind = count (2.8);
    EXPECT_EQ (behind[static_cast<int> (agex::SynthPart::LeftHand)], 0) << name;
    EXPECT_GT (behind[static_cast<int> (agex::SynthPart::RightHand)], 5) << name;
    EXPECT_GT (behind[static_cast<int> (agex::SynthPart::Torso)], 100) << name;
    // In front of it (2.2 m): labelled, and the torso loses those pixels.
    auto front = count (2.2);
    EXPECT_GT (front[static_cast<int> (agex::SynthPart::LeftHand)], 5) << name;
    EXPECT_LT (front[static_cast<int> (agex::SynthPart::Torso)], behind[static_cast<int> (agex::SynthPart::Torso)])
        << name;
    // Room pixels are 0, never a part.
    EXPECT_GT (behind[0], 1000) << name;
  }
}

// A person primitive without a part is labelled "body, part unknown"; the room never.
TEST (SynthPartLabels, PartAtNamesEveryBodySurface)
{
  auto capsule = agex::SynthPrimitive::capsule ({0, 0, 0}, {0, 1, 0}, 0.1, agex::SynthObject::Person);
  EXPECT_EQ (capsule.partAt (-1), agex::SynthPart::Unknown);
  capsule.part = agex::SynthPart::LeftForearm;
  EXPECT_EQ (capsule.partAt (-1), agex::SynthPart::LeftForearm);
  auto wall = agex::SynthPrimitive::plane ({0, 0, -1}, -4.0, agex::SynthObject::Wall);
  wall.part = agex::SynthPart::Head;
  EXPECT_EQ (wall.partAt (-1), agex::SynthPart::None);
  auto mesh = agex::SynthPrimitive::triangleMesh (
      std::make_shared<const agex::SynthMesh> (std::vector<Eigen::Vector3d>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}},
                                               std::vector<Eigen::Vector3i>{{0, 1, 2}, {1, 3, 2}}),
      agex::SynthObject::Person);
  mesh.part = agex::SynthPart::Torso;
  mesh.triangle_parts = std::make_shared<const std::vector<agex::SynthPart>> (
      std::vector<agex::SynthPart>{agex::SynthPart::LeftHand, agex::SynthPart::RightHand});
  int triangle = -1;
  ASSERT_GT (mesh.intersect ({0.8, 0.8, 1.0}, {0, 0, -1}, 0.0, nullptr, &triangle), 0.0);
  EXPECT_EQ (triangle, 1);
  EXPECT_EQ (mesh.partAt (triangle), agex::SynthPart::RightHand);
  EXPECT_EQ (mesh.partAt (0), agex::SynthPart::LeftHand);
  EXPECT_EQ (mesh.partAt (-1), agex::SynthPart::Torso) << "no triangle: the primitive's part";
  // Names: every part, and the dataset's part_labels.
  const auto names = agex::synthPartNames ();
  EXPECT_EQ (names.size (), 17u);
  EXPECT_EQ (names.at (1), "head");
  EXPECT_EQ (names.at (9), "left_hand");
  EXPECT_EQ (names.at (16), "right_foot");
  EXPECT_EQ (names.at (255), "body");
  EXPECT_EQ (names.count (0), 0u);
}

// Each triangle of the MakeHuman body is labelled by its heaviest bone: every part has
// triangles, the tips lie on their own part, left and right are mirror images.
TEST (SynthPartLabels, MeshTrianglesAreLabelledByTheirHeaviestBone)
{
  AGEX_REQUIRE_MAKEHUMAN ();
  const agex::HumanMesh mesh = agex::HumanMesh::load (sharedData ("makehuman"));
  ASSERT_EQ (mesh.triangleLabels ().size (), mesh.triangles ().size ());
  ASSERT_EQ (mesh.boneLabels ().size (), mesh.bones ().size ());
  std::map<agex::SynthPart, int> count;
  for (const auto label : mesh.triangleLabels ())
    ++count[label];
  for (int p = 1; p <= 16; ++p)
    EXPECT_GT (count[static_cast<agex::SynthPart> (p)], 100) << agex::synthPartName (static_cast<agex::SynthPart> (p));
  EXPECT_EQ (count[agex::SynthPart::LeftHand], count[agex::SynthPart::RightHand]);
  EXPECT_EQ (count[agex::SynthPart::LeftForearm], count[agex::SynthPart::RightForearm]);
  EXPECT_EQ (count[agex::SynthPart::LeftFoot], count[agex::SynthPart::RightFoot]);
  EXPECT_EQ (mesh.boneLabels ()[static_cast<std::size_t> (mesh.bone ("finger3-3.L"))], agex::SynthPart::LeftHand);
  EXPECT_EQ (mesh.boneLabels ()[static_cast<std::size_t> (mesh.bone ("lowerarm02.R"))], agex::SynthPart::RightForearm);
  EXPECT_EQ (mesh.boneLabels ()[static_cast<std::size_t> (mesh.bone ("neck02"))], agex::SynthPart::Neck);
  EXPECT_EQ (mesh.boneLabels ()[static_cast<std::size_t> (mesh.bone ("spine02"))], agex::SynthPart::Torso);
  EXPECT_EQ (mesh.boneLabels ()[static_cast<std::size_t> (mesh.bone ("root"))], agex::SynthPart::Pelvis);
  const std::pair<agex::HumanMesh::Part, agex::SynthPart> tips[] = {
      {agex::HumanMesh::Head, agex::SynthPart::Head},
      {agex::HumanMesh::LeftHand, agex::SynthPart::LeftHand},
      {agex::HumanMesh::RightHand, agex::SynthPart::RightHand},
      {agex::HumanMesh::LeftFoot, agex::SynthPart::LeftFoot},
      {agex::HumanMesh::RightFoot, agex::SynthPart::RightFoot}};
  for (const auto &[tip_part, label] : tips)
  {
    const int tip = mesh.tipVertices ()[tip_part];
    int on_part = 0;
    for (std::size_t t = 0; t < mesh.triangles ().size (); ++t)
      if ((mesh.triangles ()[t].array () == tip).any ())
        on_part += mesh.triangleLabels ()[t] == label;
    EXPECT_GT (on_part, 0) << agex::synthPartName (label) << ": the tip vertex has no triangle of its part";
  }
}

// The label images a run writes read back through the dataset, pixel for pixel.
TEST (SynthPartLabels, LabelImagesRoundTripThroughTheDataset)
{
  AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_131_01.bvh"));
  QuietPcl quiet;
  TempDir dir;
  agex::SynthOptions options;
  options.motion_files = {sharedData ("mocap/cmu_131_01.bvh")};
  options.sensor = agex::SynthSensor::Bonn;
  options.seed = 8;
  const agex::SynthGenerator gen (options);
  agex::writeSyntheticDataset (gen, 3, dir.file ("ds"), false);
  const agex::Dataset ds = agex::Dataset::read (dir.file ("ds"));
  ASSERT_TRUE (ds.hasPartLabels ());
  ASSERT_TRUE (ds.hasPersonLabels ());
  EXPECT_EQ (ds.info ().part_labels, agex::synthPartNames ());
  EXPECT_EQ (ds.partLabelPath ("000001"), (fs::path (dir.file ("ds")) / "labels" / "000001.png").string ());
  for (std::size_t f = 0; f < 3; ++f)
  {
    const agex::SynthFrame frame = gen.render (f);
    const std::string id = agex::synthFrameId (f);
    const cv::Mat parts = ds.loadPartLabels (id), persons = ds.loadPersonLabels (id);
    ASSERT_EQ (parts.type (), CV_8UC1);
    ASSERT_EQ (parts.cols, gen.sensor ().width);
    ASSERT_EQ (parts.rows, gen.sensor ().height);
    const auto cloud = ds.loadFrame (id);
    int body = 0;
    for (int v = 0; v < parts.rows; ++v)
      for (int u = 0; u < parts.cols; ++u)
      {
        const std::size_t i = static_cast<std::size_t> (v) * parts.cols + u;
        ASSERT_EQ (parts.at<std::uint8_t> (v, u), frame.part_label[i]);
        ASSERT_EQ (persons.at<std::uint8_t> (v, u), frame.person_label[i]);
        if (parts.at<std::uint8_t> (v, u))
        {
          ++body;
          ASSERT_TRUE (isFinite ((*cloud) (u, v))) << "a labelled pixel without depth in the stored frame";
          ASSERT_EQ (persons.at<std::uint8_t> (v, u), 1) << "one person: person 1";
        }
      }
    EXPECT_GT (body, 100);
    for (const auto &l : ds.labelsOf (id))
      EXPECT_EQ (l.person, 1);
  }
}
}  // namespace

namespace
{
// The Kinect's correlation window hands a fingertip's pixel to the wall behind it; the hand
// is still in view, so its label must stay visible (labelWindow follows the window).
TEST (SynthPartLabels, TheCorrelationWindowKeepsVisibleHandsLabelled)
{
  AGEX_REQUIRE_MOCAP (sharedData ("mocap/cmu_131_01.bvh"));
  AGEX_REQUIRE_MAKEHUMAN ();
  agex::SynthOptions options;
  options.motion_files = {sharedData ("mocap/cmu_131_01.bvh")};
  options.sensor = agex::SynthSensor::Kinect;
  options.body_mesh = sharedData ("makehuman");
  options.min_distance = 1.8;
  options.max_distance = 2.4;
  options.seed = 31;
  const agex::SynthGenerator plain (options);
  options.kinect_window = 9;
  const agex::SynthGenerator windowed (options);
  EXPECT_EQ (agex::labelWindow (plain.sensor ()), 2);
  EXPECT_EQ (agex::labelWindow (windowed.sensor ()), 4);
  int visible_plain = 0, visible_windowed = 0;
  for (std::uint64_t i = 0; i < 8; ++i)
  {
    const agex::SynthFrame a = plain.render (i), b = windowed.render (i);
    ASSERT_EQ (a.labels.size (), b.labels.size ());
    for (std::size_t l = 0; l < a.labels.size (); ++l)
      if (a.labels[l].part == agex::BodyPart::Hand)
      {
        visible_plain += a.labels[l].visible;
        visible_windowed += b.labels[l].visible;
      }
  }
  EXPECT_GE (visible_plain, 8) << "the clip's hands are in view";
  EXPECT_GE (visible_windowed * 10, visible_plain * 8) << visible_windowed << " of " << visible_plain
                                                        << " visible hands stay visible under the window";
}
}  // namespace
