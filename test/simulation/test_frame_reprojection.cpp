// agex::FrameReprojection (a real frame meshed, moved, rendered by a target sensor; its labels
// moved and depth-tested), depthFrameScene and writeReprojectedDataset: a synthetic person and
// a plane + box scene as input (exact depth and Kinect depth), and a real Bonn keyframe moved
// to 4 m when ../shared/data/bonn is present.
#include <agex/filters/person_segmentation.h>
#include <agex/io/bonn.h>
#include <agex/io/dataset.h>
#include <agex/io/frame_io.h>
#include <agex/simulation/dataset_reprojection.h>
#include <agex/simulation/depth_frame_mesh.h>
#include <agex/simulation/frame_reprojection.h>
#include <agex/simulation/synthetic_scene.h>

#include "test_support.h"

#include <gtest/gtest.h>

#include <opencv2/core/mat.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace
{
using Cloud = pcl::PointCloud<pcl::PointXYZ>;
const float kNaN = std::numeric_limits<float>::quiet_NaN ();

const agex::CameraIntrinsics kKinect;  // 525, 525, 319.5, 239.5

agex::SensorModel
exact640 ()
{
  return agex::exactDepthSensor (640, 480, kKinect);
}

agex::SynthFrame
render (const agex::SynthScene &scene, const agex::SensorModel &model, std::uint64_t seed = 1)
{
  agex::SynthRng rng (seed);
  agex::SynthFrame frame;
  agex::renderScene (scene, model, rng, frame);
  return frame;
}

/** A wall at 3 m and a 0.6 m box whose front is at 1.7 m, in the middle of the view. */
agex::SynthScene
wallAndBox ()
{
  agex::SynthScene scene;
  scene.primitives.push_back (agex::SynthPrimitive::plane (Eigen::Vector3d::UnitZ (), 3.0, agex::SynthObject::Wall));
  scene.primitives.push_back (
      agex::SynthPrimitive::box (Eigen::Vector3d (0, 0, 2.0), 0.3 * Eigen::Matrix3d::Identity (), agex::SynthObject::Clutter));
  return scene;
}

/** A synthetic person (procedural pose, capsule body) 2 m away in a room: the generator's
  * scene. */
agex::SynthFrame
personFrame ()
{
  agex::SynthOptions options;
  options.procedural_poses = 20;
  options.sensor = agex::SynthSensor::Kinect;
  options.min_distance = options.max_distance = 2.0;
  options.clutter = false;
  options.seed = 5;
  const agex::SynthGenerator generator (options);
  return generator.render (3);
}

cv::Mat
toImage (const std::vector<std::uint8_t> &values, int width, int height)
{
  cv::Mat image (height, width, CV_8UC1, cv::Scalar (0));
  std::copy (values.begin (), values.end (), image.data);
  return image;
}

Cloud::Ptr
shared (const Cloud &cloud)
{
  return Cloud::Ptr (new Cloud (cloud));
}

/** Valid pixels of a person image (> 0) and their median depth. */
std::size_t
personPixels (const Cloud &cloud, const cv::Mat &persons, double *median_depth = nullptr)
{
  std::vector<double> z;
  for (std::size_t i = 0; i < cloud.points.size (); ++i)
    if (persons.data[i] > 0 && std::isfinite (cloud.points[i].z))
      z.push_back (cloud.points[i].z);
  if (median_depth)
  {
    std::nth_element (z.begin (), z.begin () + z.size () / 2, z.end ());
    *median_depth = z.empty () ? std::nan ("") : z[z.size () / 2];
  }
  return z.size ();
}

std::size_t
validPixels (const Cloud &cloud)
{
  return static_cast<std::size_t> (
      std::count_if (cloud.points.begin (), cloud.points.end (), [] (const pcl::PointXYZ &p) { return std::isfinite (p.z); }));
}

agex::PartLabel
labelAt (const Eigen::Vector3f &tip, agex::BodyPart part = agex::BodyPart::Hand)
{
  agex::PartLabel label;
  label.part = part;
  label.tip = tip;
  label.base = tip + Eigen::Vector3f (0, 0.1f, 0);
  label.visible = true;
  return label;
}

Eigen::Vector2f
projected (const agex::CameraIntrinsics &k, const Eigen::Vector3d &p)
{
  return Eigen::Vector2f (static_cast<float> (k.fx * p.x () / p.z () + k.cx), static_cast<float> (k.fy * p.y () / p.z () + k.cy));
}
}  // namespace

// Moved by nothing and measured by the exact-depth sensor, the frame comes back: every pixel
// inside a surface has its depth; only pixels on a surface's edge may be lost (the mesh runs
// through the pixel centres, so a ray through an edge pixel's centre grazes the mesh's edge and
// hits or misses it by rounding: about half of them are lost).
TEST (FrameReprojection, NoMoveWithExactDepthReproducesTheFrame)
{
  const agex::SynthFrame person = personFrame ();
  const agex::SynthFrame input = render (person.scene, exact640 ());
  agex::FrameReprojection reprojection;
  reprojection.setInputCloud (shared (input.cloud));
  reprojection.setTargetSensor (exact640 ());
  agex::DepthMeshSettings exact;
  exact.depth_step_growth = 0.0;
  exact.depth_quantum = 0.002;
  reprojection.setMeshSettings (exact);
  agex::ReprojectedFrame out;
  reprojection.compute (out);
  ASSERT_EQ (out.cloud.width, 640u);
  ASSERT_EQ (out.cloud.height, 480u);
  EXPECT_GT (out.mesh.triangles, 400000u);
  std::size_t valid_in = 0, kept = 0, added = 0;
  double worst = 0.0;
  for (std::size_t i = 0; i < input.cloud.points.size (); ++i)
  {
    const float zi = input.cloud.points[i].z, zo = out.cloud.points[i].z;
    valid_in += std::isfinite (zi);
    added += !std::isfinite (zi) && std::isfinite (zo);
    if (std::isfinite (zi) && std::isfinite (zo))
    {
      ++kept;
      worst = std::max (worst, static_cast<double> (std::abs (zi - zo)));
    }
  }
  ASSERT_GT (valid_in, 250000u);
  // Every pixel lost lies on a surface's edge: its 3x3 block has a pixel without depth or two
  // neighbours not joined (DepthMeshSettings::maxGap), so some triangle around it is missing.
  auto joined = [&] (const pcl::PointXYZ &p, const pcl::PointXYZ &q) {
    if (!std::isfinite (p.z) || !std::isfinite (q.z))
      return false;
    const double near = std::min (p.z, q.z);
    const double lateral = near * std::hypot (p.x / p.z - q.x / q.z, p.y / p.z - q.y / q.z);
    return std::abs (q.z - p.z) <= exact.maxGap (near, lateral);
  };
  std::size_t lost_inside = 0;
  for (int v = 1; v < 479; ++v)
    for (int u = 1; u < 639; ++u)
    {
      if (!std::isfinite (input.cloud (u, v).z) || std::isfinite (out.cloud (u, v).z))
        continue;
      bool edge = false;
      for (int a = 0; a < 9; ++a)
        for (int b = 0; b < 9; ++b)
        {
          const int ua = u + a % 3 - 1, va = v + a / 3 - 1, ub = u + b % 3 - 1, vb = v + b / 3 - 1;
          if (a != b && std::abs (ua - ub) <= 1 && std::abs (va - vb) <= 1)
            edge = edge || !joined (input.cloud (ua, va), input.cloud (ub, vb));
        }
      lost_inside += !edge;
    }
  EXPECT_EQ (lost_inside, 0u);
  EXPECT_GT (static_cast<double> (kept), 0.99 * valid_in);
  EXPECT_EQ (added, 0u);
  EXPECT_LT (worst, 1e-4);
}

// A Kinect frame of a person at 2 m (disparity steps of 1.2 cm, noise, holes at edges) meshed
// with the Kinect's steps: the person's surface stays closed (the re-rendered person keeps
// nearly all of its pixels); meshed as if its depth were exact, it tears.
TEST (FrameReprojection, KinectPersonAtTwoMetresStaysClosed)
{
  const agex::SynthFrame person = personFrame ();
  const agex::SynthFrame kinect = render (person.scene, agex::sensorModel (agex::SynthSensor::Kinect), 9);
  agex::FrameReprojection reprojection;
  reprojection.setInputCloud (shared (kinect.cloud));
  reprojection.setPersonImage (toImage (kinect.person_label, 640, 480));
  reprojection.setTargetSensor (exact640 ());
  agex::ReprojectedFrame out;
  reprojection.compute (out);
  const cv::Mat in_persons = toImage (kinect.person_label, 640, 480);
  const std::size_t before = personPixels (kinect.cloud, in_persons);
  ASSERT_GT (before, 8000u);
  std::size_t kept = 0;
  for (std::size_t i = 0; i < kinect.cloud.points.size (); ++i)
    kept += in_persons.data[i] > 0 && std::isfinite (out.cloud.points[i].z);
  EXPECT_GT (static_cast<double> (kept), 0.95 * before);

  // Without the Kinect's steps (an exact-depth source), the person falls apart into strips.
  agex::DepthMeshSettings tight;
  tight.depth_step_growth = 0.0;
  tight.depth_quantum = 0.001;
  tight.gap_slope = 1.0;
  reprojection.setMeshSettings (tight);
  agex::ReprojectedFrame torn;
  reprojection.compute (torn);
  std::size_t kept_tight = 0;
  for (std::size_t i = 0; i < kinect.cloud.points.size (); ++i)
    kept_tight += in_persons.data[i] > 0 && std::isfinite (torn.cloud.points[i].z);
  EXPECT_LT (static_cast<double> (kept_tight), 0.8 * before) << "the default gap must be what closes the surface";
}

// The plane + box scene moved 1 m back: nothing appears between the box's front and the
// wall (the silhouette is not bridged), and the box's pixels shrink by (z / (z + 1))^2.
TEST (FrameReprojection, SilhouettesAreNotBridged)
{
  const agex::SynthFrame input = render (wallAndBox (), exact640 ());
  agex::FrameReprojection reprojection;
  reprojection.setInputCloud (shared (input.cloud));
  reprojection.setTargetSensor (exact640 ());
  agex::ReprojectionMove move;
  move.dz = 1.0;
  reprojection.setMove (move);
  agex::ReprojectedFrame out;
  reprojection.compute (out);
  std::size_t between = 0, box_before = 0, box_after = 0;
  for (std::size_t i = 0; i < out.cloud.points.size (); ++i)
  {
    const float z = out.cloud.points[i].z;
    between += std::isfinite (z) && z > 2.8f && z < 3.9f;
    box_after += std::isfinite (z) && z < 2.8f;
    box_before += input.cloud.points[i].z < 1.8f;
  }
  EXPECT_EQ (between, 0u);
  const double expected = box_before * std::pow (1.7 / 2.7, 2.0);
  EXPECT_NEAR (static_cast<double> (box_after), expected, 0.03 * expected);
}

// A floor 1 m below the camera with a box on it, moved 2 m back: without the floor plane the
// bottom of the frame (floor nearer than the recording saw) is empty; with it, those pixels show
// the floor at its exact depth, the recorded surfaces still show, and the box's labels stay
// visible. An empty frame, or one moved behind the camera, stays empty with a floor plane.
TEST (FrameReprojection, FloorPlaneFillsTheFloorTheRecordingDidNotSee)
{
  agex::SynthScene room;
  room.primitives.push_back (agex::SynthPrimitive::plane (-Eigen::Vector3d::UnitY (), -1.0, agex::SynthObject::Floor));
  room.primitives.push_back (agex::SynthPrimitive::plane (Eigen::Vector3d::UnitZ (), 6.0, agex::SynthObject::Wall));
  room.primitives.push_back (agex::SynthPrimitive::box (Eigen::Vector3d (0, 0.7, 3.0), 0.3 * Eigen::Matrix3d::Identity (),
                                                        agex::SynthObject::Clutter));
  const agex::SynthFrame input = render (room, exact640 ());
  agex::FrameReprojection reprojection;
  reprojection.setInputCloud (shared (input.cloud));
  reprojection.setLabels ({labelAt (Eigen::Vector3f (0.0f, 0.4f, 2.7f))});
  reprojection.setTargetSensor (exact640 ());
  agex::ReprojectionMove move;
  move.dz = 2.0;
  reprojection.setMove (move);
  agex::ReprojectedFrame bare, floored;
  reprojection.compute (bare);
  // n.p + d = height above the floor: up is -y, the camera 1 m above it.
  reprojection.setFloorPlane (Eigen::Vector4f (0.0f, -2.0f, 0.0f, 2.0f));
  EXPECT_TRUE (reprojection.hasFloorPlane ());
  reprojection.compute (floored);
  std::size_t bottom_bare = 0, bottom_floored = 0, off_plane = 0, changed = 0;
  for (int v = 440; v < 480; ++v)
    for (int u = 0; u < 640; ++u)
    {
      bottom_bare += std::isfinite (bare.cloud (u, v).z);
      const pcl::PointXYZ &p = floored.cloud (u, v);
      bottom_floored += std::isfinite (p.z);
      off_plane += std::isfinite (p.z) && std::abs (p.y - 1.0f) > 1e-3f;
    }
  for (std::size_t i = 0; i < bare.cloud.points.size (); ++i)
    changed += std::isfinite (bare.cloud.points[i].z) && std::abs (bare.cloud.points[i].z - floored.cloud.points[i].z) > 1e-3f;
  EXPECT_EQ (bottom_bare, 0u);
  EXPECT_EQ (bottom_floored, 40u * 640u);
  EXPECT_EQ (off_plane, 0u);
  EXPECT_EQ (changed, 0u) << "the recorded surfaces show where they are";
  ASSERT_EQ (floored.labels.size (), 1u);
  EXPECT_TRUE (floored.labels[0].visible);

  move.dz = -10.0;
  reprojection.setMove (move);
  agex::ReprojectedFrame behind;
  reprojection.compute (behind);
  EXPECT_EQ (validPixels (behind.cloud), 0u);
  reprojection.setInputCloud (Cloud::Ptr (new Cloud (640, 480, pcl::PointXYZ (kNaN, kNaN, kNaN))));
  reprojection.setMove (agex::ReprojectionMove ());
  agex::ReprojectedFrame empty;
  reprojection.compute (empty);
  EXPECT_EQ (validPixels (empty.cloud), 0u);
  reprojection.clearFloorPlane ();
  EXPECT_FALSE (reprojection.hasFloorPlane ());
  EXPECT_THROW (reprojection.setFloorPlane (Eigen::Vector4f (0.0f, 0.0f, 0.0f, 1.0f)), std::invalid_argument);
  EXPECT_THROW (reprojection.setFloorPlane (Eigen::Vector4f (0.0f, kNaN, 0.0f, 1.0f)), std::invalid_argument);
}

// The person moved 1 m back: the median depth of its pixels grows by 1 m and their number
// shrinks by about (z / (z + 1))^2, with the exact sensor and with the Kinect model.
TEST (FrameReprojection, OneMetreBackShrinksThePersonByTheSquareOfTheDepthRatio)
{
  const agex::SynthFrame person = personFrame ();
  const agex::SynthFrame input = render (person.scene, exact640 ());
  const cv::Mat persons = toImage (input.person_label, 640, 480);
  double z0 = 0.0;
  const std::size_t n0 = personPixels (input.cloud, persons, &z0);
  ASSERT_GT (n0, 8000u);
  ASSERT_NEAR (z0, 2.0, 0.3);
  EXPECT_NEAR (agex::FrameReprojection::personMedianDepth (input.cloud, {}, persons), z0, 0.01);

  agex::FrameReprojection reprojection;
  reprojection.setInputCloud (shared (input.cloud));
  reprojection.setPersonImage (persons);
  agex::ReprojectionMove move;
  move.dz = 1.0;
  reprojection.setMove (move);
  const double expected = n0 * std::pow (z0 / (z0 + 1.0), 2.0);
  for (const agex::SensorModel &model : {exact640 (), agex::sensorModel (agex::SynthSensor::Kinect)})
  {
    SCOPED_TRACE (agex::synthSensorName (model.sensor));
    reprojection.setTargetSensor (model);
    agex::ReprojectedFrame out;
    reprojection.compute (out);
    ASSERT_FALSE (out.persons.empty ());
    double z1 = 0.0;
    const std::size_t n1 = personPixels (out.cloud, out.persons, &z1);
    EXPECT_NEAR (z1, z0 + 1.0, 0.03);
    // The Kinect loses pixels on depth edges (kinect_edge_drop) and in projector shadows.
    EXPECT_NEAR (static_cast<double> (n1), expected, (model.sensor == agex::SynthSensor::Kinect ? 0.15 : 0.05) * expected);
  }
}

// Labels move with the scene (tilt included) and are projected with the target's intrinsics;
// a label behind the box is hidden, one beside it is not; one moved out of the frame is hidden;
// one behind the camera or without a 3D tip is left out.
TEST (FrameReprojection, LabelsMoveProjectAndAreDepthTested)
{
  const agex::SynthFrame input = render (wallAndBox (), exact640 ());
  const std::vector<agex::PartLabel> labels{
      labelAt (Eigen::Vector3f (0.0f, 0.0f, 3.0f)),       // on the wall behind the box
      labelAt (Eigen::Vector3f (1.0f, 0.2f, 3.0f)),       // on the wall, in view
      labelAt (Eigen::Vector3f (0.1f, -0.1f, 1.7f)),      // on the box's front
      labelAt (Eigen::Vector3f (kNaN, kNaN, kNaN)),       // never lifted to 3D
  };
  agex::FrameReprojection reprojection;
  reprojection.setInputCloud (shared (input.cloud));
  reprojection.setLabels (labels);
  reprojection.setTargetSensor (exact640 ());
  agex::ReprojectedFrame still;
  reprojection.compute (still);
  ASSERT_EQ (still.labels.size (), 3u);
  EXPECT_EQ (still.dropped_labels, 1u);
  EXPECT_FALSE (still.labels[0].visible);
  EXPECT_TRUE (still.labels[1].visible);
  EXPECT_TRUE (still.labels[2].visible);

  agex::ReprojectionMove move;
  move.dx = 0.25;
  move.dy = -0.1;
  move.dz = 0.8;
  move.tilt_deg = 6.0;
  reprojection.setMove (move);
  agex::ReprojectedFrame moved;
  reprojection.compute (moved);
  ASSERT_EQ (moved.labels.size (), 3u);
  const Eigen::Isometry3d t = move.transform ();
  // The camera pitched up: a point straight ahead appears lower (v grows).
  EXPECT_GT ((t * Eigen::Vector3d (0, 0, 3)).y (), 0.0);
  for (std::size_t k = 0; k < 3; ++k)
  {
    const Eigen::Vector3d tip = t * labels[k].tip.cast<double> (), base = t * labels[k].base.cast<double> ();
    EXPECT_TRUE (moved.labels[k].tip.isApprox (tip.cast<float> (), 1e-5f));
    EXPECT_TRUE (moved.labels[k].base.isApprox (base.cast<float> (), 1e-5f));
    EXPECT_TRUE (moved.labels[k].tip_px.isApprox (projected (kKinect, tip), 1e-4f));
    EXPECT_TRUE (moved.labels[k].base_px.isApprox (projected (kKinect, base), 1e-4f));
  }
  EXPECT_FALSE (moved.labels[0].visible);
  EXPECT_TRUE (moved.labels[1].visible);
  EXPECT_TRUE (moved.labels[2].visible);

  move = agex::ReprojectionMove ();
  move.dx = 3.0;  // the wall label at x = 4 m, 3 m away: u = 1020, outside
  reprojection.setMove (move);
  agex::ReprojectedFrame aside;
  reprojection.compute (aside);
  ASSERT_EQ (aside.labels.size (), 3u);
  EXPECT_GT (aside.labels[1].tip_px.x (), 640.0f);
  EXPECT_FALSE (aside.labels[1].visible);

  move = agex::ReprojectionMove ();
  move.dz = -2.0;  // the box's front at -0.3 m, the wall at 1 m
  reprojection.setMove (move);
  agex::ReprojectedFrame behind;
  reprojection.compute (behind);
  EXPECT_EQ (behind.labels.size (), 2u);
  EXPECT_EQ (behind.dropped_labels, 2u);
}

// 640x480 to 320x240 (scaledTo: the same field of view): every label lands on half its pixel
// coordinates (pixel edges kept: (u + 0.5) / 2 - 0.5), and the box covers a quarter of the pixels.
TEST (FrameReprojection, HalfResolutionHalvesThePixelCoordinates)
{
  const agex::SynthFrame input = render (wallAndBox (), exact640 ());
  const std::vector<agex::PartLabel> labels{labelAt (Eigen::Vector3f (1.0f, 0.2f, 3.0f)),
                                            labelAt (Eigen::Vector3f (0.1f, -0.1f, 1.7f))};
  agex::FrameReprojection reprojection;
  reprojection.setInputCloud (shared (input.cloud));
  reprojection.setLabels (labels);
  agex::ReprojectionMove move;
  move.dx = -0.2;
  move.dz = 0.5;
  reprojection.setMove (move);
  reprojection.setTargetSensor (exact640 ());
  agex::ReprojectedFrame full, half;
  reprojection.compute (full);
  reprojection.setTargetSensor (agex::scaledTo (exact640 (), 320, 240));
  reprojection.compute (half);
  ASSERT_EQ (half.cloud.width, 320u);
  ASSERT_EQ (half.cloud.height, 240u);
  ASSERT_EQ (half.labels.size (), 2u);
  for (std::size_t k = 0; k < 2; ++k)
  {
    EXPECT_NEAR (half.labels[k].tip_px.x () + 0.5f, (full.labels[k].tip_px.x () + 0.5f) / 2.0f, 1e-3f);
    EXPECT_NEAR (half.labels[k].tip_px.y () + 0.5f, (full.labels[k].tip_px.y () + 0.5f) / 2.0f, 1e-3f);
    EXPECT_EQ (half.labels[k].visible, full.labels[k].visible);
    EXPECT_TRUE (half.labels[k].visible);
  }
  auto box = [] (const Cloud &c) {
    return std::count_if (c.points.begin (), c.points.end (), [] (const pcl::PointXYZ &p) { return p.z < 2.5f; });
  };
  EXPECT_NEAR (static_cast<double> (box (half.cloud)), box (full.cloud) / 4.0, 0.04 * box (full.cloud) / 4.0);
}

// The bonn target: a kinect render made into the 144x176 portrait view, in 8-bit depth levels
// that end at 4.09 m (beyond: nothing, and labels there are hidden), or with the kinect's depth.
TEST (FrameReprojection, BonnTargetIsThePortraitViewWithOrWithoutItsDepthLevels)
{
  const agex::SynthFrame input = render (wallAndBox (), exact640 ());
  agex::FrameReprojection reprojection;
  reprojection.setInputCloud (shared (input.cloud));
  reprojection.setLabels ({labelAt (Eigen::Vector3f (0.1f, -0.1f, 1.7f))});
  reprojection.setTargetSensor (agex::sensorModel (agex::SynthSensor::Bonn));
  agex::ReprojectionMove move;
  move.dz = 2.8;  // the box's front at 4.5 m
  reprojection.setMove (move);
  agex::ReprojectedFrame levels, kinect;
  reprojection.compute (levels);
  reprojection.setBonnDepthLevels (false);
  reprojection.compute (kinect);
  for (const agex::ReprojectedFrame *f : {&levels, &kinect})
  {
    EXPECT_EQ (f->cloud.width, 144u);
    EXPECT_EQ (f->cloud.height, 176u);
  }
  EXPECT_EQ (validPixels (levels.cloud), 0u);
  EXPECT_FALSE (levels.labels[0].visible);
  EXPECT_GT (validPixels (kinect.cloud), 500u);
  EXPECT_TRUE (kinect.labels[0].visible);
  const agex::CameraIntrinsics k = agex::sensorModel (agex::SynthSensor::Bonn).intrinsics;
  EXPECT_TRUE (kinect.labels[0].tip_px.isApprox (projected (k, Eigen::Vector3d (0.1, -0.1, 4.5)), 1e-4f));
  // Nearer, the 8-bit levels hold the box: its depths are multiples of 1.6 cm.
  move.dz = 1.0;
  reprojection.setMove (move);
  reprojection.setBonnDepthLevels (true);
  reprojection.compute (levels);
  std::size_t on_levels = 0, valid = 0;
  for (const auto &p : levels.cloud.points)
    if (std::isfinite (p.z))
    {
      ++valid;
      on_levels += std::abs (p.z / agex::kBonnDepthStep - std::round (p.z / agex::kBonnDepthStep)) < 1e-3;
    }
  EXPECT_GT (valid, 10000u);
  EXPECT_EQ (on_levels, valid);
}

// Nothing to mesh, or everything moved behind the camera: a frame of the target's size without
// a valid pixel, and no crash.
TEST (FrameReprojection, EmptyAllNaNAndBehindTheCameraGiveAnEmptyFrame)
{
  const std::vector<agex::PartLabel> labels{labelAt (Eigen::Vector3f (kNaN, kNaN, kNaN))};
  std::vector<Cloud::Ptr> inputs{Cloud::Ptr (new Cloud),
                                 Cloud::Ptr (new Cloud (640, 480, pcl::PointXYZ (kNaN, kNaN, kNaN))),
                                 Cloud::Ptr (new Cloud (640, 1, pcl::PointXYZ (0.0f, 0.0f, 2.0f))), nullptr};
  for (const Cloud::Ptr &cloud : inputs)
  {
    agex::FrameReprojection reprojection;
    reprojection.setInputCloud (cloud);
    reprojection.setLabels (labels);
    for (const agex::SensorModel &model : {exact640 (), agex::sensorModel (agex::SynthSensor::Kinect),
                                           agex::sensorModel (agex::SynthSensor::Bonn)})
    {
      reprojection.setTargetSensor (model);
      agex::ReprojectedFrame out;
      reprojection.compute (out);
      EXPECT_EQ (out.cloud.width, static_cast<std::uint32_t> (model.width));
      EXPECT_EQ (out.cloud.height, static_cast<std::uint32_t> (model.height));
      EXPECT_EQ (validPixels (out.cloud), 0u);
      EXPECT_TRUE (out.labels.empty ());
      EXPECT_EQ (out.mesh.triangles, 0u);
    }
  }
  // The whole scene behind the camera.
  const agex::SynthFrame input = render (wallAndBox (), exact640 ());
  agex::FrameReprojection reprojection;
  reprojection.setInputCloud (shared (input.cloud));
  reprojection.setLabels ({labelAt (Eigen::Vector3f (0.1f, -0.1f, 1.7f))});
  agex::ReprojectionMove move;
  move.dz = -10.0;
  reprojection.setMove (move);
  agex::ReprojectedFrame out;
  reprojection.compute (out);
  EXPECT_EQ (validPixels (out.cloud), 0u);
  EXPECT_TRUE (out.labels.empty ());
  EXPECT_EQ (out.dropped_labels, 1u);
}

// Settings out of range are refused by name.
TEST (FrameReprojection, OutOfRangeSettingsThrowNamingThem)
{
  auto message = [] (const std::function<void ()> &call) {
    try
    {
      call ();
    }
    catch (const std::invalid_argument &e)
    {
      return std::string (e.what ());
    }
    return std::string ("(no exception)");
  };
  agex::FrameReprojection r;
  agex::ReprojectionMove move;
  move.tilt_deg = 95.0;
  EXPECT_NE (message ([&] { r.setMove (move); }).find ("tilt"), std::string::npos);
  move = agex::ReprojectionMove ();
  move.dz = std::nan ("");
  EXPECT_NE (message ([&] { r.setMove (move); }).find ("dz"), std::string::npos);
  agex::DepthMeshSettings mesh;
  mesh.gap_steps = 0.0;
  EXPECT_NE (message ([&] { r.setMeshSettings (mesh); }).find ("gap_steps"), std::string::npos);
  mesh = agex::DepthMeshSettings ();
  mesh.depth_step_growth = 1.0;
  EXPECT_NE (message ([&] { r.setMeshSettings (mesh); }).find ("depth_step_growth"), std::string::npos);
  mesh = agex::DepthMeshSettings ();
  mesh.gap_slope = -1.0;
  EXPECT_NE (message ([&] { r.setMeshSettings (mesh); }).find ("gap_slope"), std::string::npos);
  EXPECT_NE (message ([&] { r.setLabelTolerance (2.0); }).find ("label tolerance"), std::string::npos);
  EXPECT_NE (message ([&] { r.setTargetSensor (agex::scaledTo (agex::sensorModel (agex::SynthSensor::Bonn), 288, 352)); })
                 .find ("bonn"),
             std::string::npos);
  agex::SensorModel bad = agex::sensorModel (agex::SynthSensor::Kinect);
  bad.kinect_window = 4;
  EXPECT_NE (message ([&] { r.setTargetSensor (bad); }).find ("kinect_window"), std::string::npos);
  // A person image of another size than the frame.
  r.setInputCloud (Cloud::Ptr (new Cloud (64, 48, pcl::PointXYZ (0, 0, 2))));
  r.setPersonImage (cv::Mat (10, 10, CV_8UC1, cv::Scalar (1)));
  agex::ReprojectedFrame out;
  EXPECT_NE (message ([&] { r.compute (out); }).find ("person image"), std::string::npos);

  agex::DatasetReprojectionOptions options;
  options.copies = 0;
  EXPECT_NE (message ([&] { options.validate (); }).find ("copies"), std::string::npos);
  options = agex::DatasetReprojectionOptions ();
  options.min_distance = 0.1;
  options.max_distance = 3.0;
  EXPECT_NE (message ([&] { options.validate (); }).find ("min_distance"), std::string::npos);
  options = agex::DatasetReprojectionOptions ();
  options.min_distance = 4.0;
  options.max_distance = 3.0;
  EXPECT_NE (message ([&] { options.validate (); }).find ("max_distance"), std::string::npos);
  options = agex::DatasetReprojectionOptions ();
  options.tilt_deg = 90.0;
  EXPECT_NE (message ([&] { options.validate (); }).find ("tilt_deg"), std::string::npos);
}

// A dataset re-projected: copies per frame named <id>_c<k> in the frame's sequence, each person
// brought to a drawn distance within the range, person images carried, the same seed giving
// the same bytes; the depth quantum of a dataset is its depth scale when that is a storage step.
TEST (DatasetReprojection, WritesMovedCopiesDeterministically)
{
  agex_test::TempDir dir;
  const agex::SynthFrame person = personFrame ();
  const agex::SynthFrame input = render (person.scene, agex::sensorModel (agex::SynthSensor::Kinect), 3);
  agex::DatasetInfo info;
  info.name = "test";
  info.sensor = "kinect";
  info.width = 640;
  info.height = 480;
  info.depth_scale = 0.001;
  info.person_labels = true;
  {
    agex::DatasetWriter writer (dir.file ("in"), info);
    writer.addFrame ("a", "s1", input.cloud, person.labels);
    writer.addPersonLabels ("a", toImage (input.person_label, 640, 480));
    writer.addFrame ("b", "s2", input.cloud, person.labels);
    writer.addPersonLabels ("b", toImage (input.person_label, 640, 480));
    writer.commit ();
  }
  const agex::Dataset dataset = agex::Dataset::read (dir.file ("in"));
  EXPECT_DOUBLE_EQ (agex::depthQuantumOf (dataset.info ()), 0.001);
  agex::DatasetInfo metric = info;
  metric.depth_scale = 1.0;
  EXPECT_DOUBLE_EQ (agex::depthQuantumOf (metric), 0.0);

  agex::DatasetReprojectionOptions options;
  options.min_distance = 3.5;
  options.max_distance = 4.5;
  options.sideways = 0.6;
  options.copies = 2;
  options.seed = 11;
  options.mesh.depth_quantum = agex::depthQuantumOf (dataset.info ());
  int floors_asked = 0;
  options.find_floor = [&floors_asked] (const Cloud &, Eigen::Vector4f &plane) {
    ++floors_asked;
    plane = Eigen::Vector4f (0.0f, -1.0f, 0.0f, 1.2f);
    return floors_asked == 1;  // the first frame has one, the second not
  };
  const agex::DatasetReprojectionStats stats =
      agex::writeReprojectedDataset (dataset, {"b", "a"}, options, dir.file ("out"), false);
  EXPECT_EQ (floors_asked, 2);
  EXPECT_EQ (stats.with_floor, 1u);
  EXPECT_EQ (stats.frames_in, 2u);
  EXPECT_EQ (stats.frames_out, 4u);
  EXPECT_EQ (stats.skipped, 0u);
  const agex::Dataset out = agex::Dataset::read (dir.file ("out"));
  ASSERT_EQ (out.frames ().size (), 4u);
  EXPECT_EQ (out.frames ()[0].id, "b_c0");
  EXPECT_EQ (out.frames ()[0].sequence, "s2");
  EXPECT_EQ (out.frames ()[3].id, "a_c1");
  EXPECT_EQ (out.frames ()[3].sequence, "s1");
  EXPECT_TRUE (out.hasPersonLabels ());
  EXPECT_EQ (out.info ().width, 640);
  const double z0 = agex::FrameReprojection::personMedianDepth (input.cloud, {}, toImage (input.person_label, 640, 480));
  std::vector<double> distances;
  for (const auto &frame : out.frames ())
  {
    const Cloud::Ptr cloud = out.loadFrame (frame.id);
    double z = 0.0;
    ASSERT_GT (personPixels (*cloud, out.loadPersonLabels (frame.id), &z), 1000u);
    EXPECT_GE (z, 3.4);
    EXPECT_LE (z, 4.6);
    distances.push_back (z);
    EXPECT_EQ (out.labelsOf (frame.id).size (), person.labels.size ());
  }
  // The copies differ (their own draws), and the same frame's copies do not depend on the order.
  EXPECT_GT (std::abs (distances[0] - distances[1]), 1e-3);
  EXPECT_GT (z0, 1.5);

  // Frame a had no floor in the first run: the same again gives the same bytes.
  options.find_floor = [] (const Cloud &, Eigen::Vector4f &) { return false; };
  agex::writeReprojectedDataset (dataset, {"a"}, options, dir.file ("again"), false);
  EXPECT_EQ (agex_test::readAll (dir.file ("again/frames/a_c1.pcd")), agex_test::readAll (dir.file ("out/frames/a_c1.pcd")));
  EXPECT_EQ (agex_test::readAll (dir.file ("again/persons/a_c0.png")), agex_test::readAll (dir.file ("out/persons/a_c0.png")));
  // An existing output is not replaced without overwrite.
  EXPECT_THROW (agex::writeReprojectedDataset (dataset, {"a"}, options, dir.file ("out"), false), agex::DatasetError);

  // A distance asked for, but no frame has a person depth: nothing is written.
  agex::DatasetInfo bare = info;
  bare.person_labels = false;
  {
    agex::DatasetWriter writer (dir.file ("bare"), bare);
    writer.addFrame ("w", "s1", input.cloud, {});
    writer.commit ();
  }
  const agex::Dataset unlabelled = agex::Dataset::read (dir.file ("bare"));
  EXPECT_THROW (agex::writeReprojectedDataset (unlabelled, {"w"}, options, dir.file ("none"), false),
                std::invalid_argument);
  EXPECT_FALSE (agex_test::fs::exists (dir.file ("none")));
  std::size_t left = 0;
  for (const auto &entry : agex_test::fs::directory_iterator (dir.path ()))
    left += entry.path ().filename ().string ().find ("partial") != std::string::npos;
  EXPECT_EQ (left, 0u);
  // Without a distance the same frame is only moved sideways.
  options.min_distance = options.max_distance = 0.0;
  EXPECT_EQ (agex::writeReprojectedDataset (unlabelled, {"w"}, options, dir.file ("sideways"), false).frames_out, 2u);
}

// A real Bonn keyframe (sequence 7, person at about 2.3 m, 8-bit depth) moved to 4 m with its
// floor and seen by the Kinect model: the person is still there, its pixels scaled by
// (z0 / 4)^2 within 30%, its median depth at 4 m, found by PersonSegmentation, and its labels
// still visible.
TEST (FrameReprojectionReal, BonnKeyframeMovedToFourMetres)
{
  const std::string png = agex_test::sharedData ("bonn/depth/7/022.png");
  const std::string labels_path = agex_test::sharedData ("bonn/labels.csv");
  AGEX_REQUIRE_BONN (png);
  AGEX_REQUIRE_BONN (labels_path);
  const agex::Frame frame = agex::loadFrame (png);
  // The person: PersonSegmentation's largest person (the Bonn frames hold one).
  agex::PersonSegmentation<pcl::PointXYZ> segmentation;
  segmentation.setInputCloud (frame.cloud);
  std::vector<pcl::PointIndices> found;
  segmentation.segment (found);
  ASSERT_FALSE (found.empty ());
  cv::Mat persons (480, 640, CV_8UC1, cv::Scalar (0));
  for (const int i : found[0].indices)
    persons.data[i] = 1;
  std::vector<agex::PartLabel> labels;
  for (const agex::BonnLabel &b : agex::readBonnLabels (labels_path))
  {
    if (b.sequence != "7" || b.frame != "022")
      continue;
    agex::PartLabel label;
    label.part = b.part;
    label.instance = b.instance;
    label.keyframe = b.keyframe;
    Eigen::Vector3f tip, base;
    label.visible = agex::liftPixelToSurface (*frame.cloud, b.tip_px.x (), b.tip_px.y (), 6, 0.05f, tip);
    label.tip = label.visible ? tip : Eigen::Vector3f::Constant (kNaN);
    label.base = agex::liftPixelToSurface (*frame.cloud, b.base_px.x (), b.base_px.y (), 6, 0.05f, base)
                     ? base
                     : Eigen::Vector3f::Constant (kNaN);
    labels.push_back (label);
  }
  ASSERT_GE (labels.size (), 5u);
  ASSERT_TRUE (labels[0].keyframe);

  double z0 = 0.0;
  const std::size_t n0 = personPixels (*frame.cloud, persons, &z0);
  ASSERT_GT (n0, 10000u);
  agex::FrameReprojection reprojection;
  reprojection.setInputCloud (frame.cloud);
  reprojection.setLabels (labels);
  reprojection.setPersonImage (persons);
  agex::DepthMeshSettings mesh;
  mesh.depth_quantum = agex::kBonnDepthStep;  // the 8-bit PNG's levels
  reprojection.setMeshSettings (mesh);
  agex::ReprojectionMove move;
  move.dz = 4.0 - agex::FrameReprojection::personMedianDepth (*frame.cloud, labels, persons);
  reprojection.setMove (move);
  reprojection.setTargetSensor (agex::sensorModel (agex::SynthSensor::Kinect));
  ASSERT_TRUE (segmentation.getFloorFound ());
  reprojection.setFloorPlane (segmentation.getFloorPlane ());
  agex::ReprojectedFrame out;
  reprojection.compute (out);
  double z1 = 0.0;
  const std::size_t n1 = personPixels (out.cloud, out.persons, &z1);
  const double expected = n0 * std::pow (z0 / 4.0, 2.0);
  EXPECT_NEAR (static_cast<double> (n1), expected, 0.3 * expected) << "z0 " << z0 << " m, " << n0 << " pixels";
  EXPECT_NEAR (z1, 4.0, 0.1);
  // PersonSegmentation finds the moved person on its own, on the floor, at 4 m, with about
  // the pixels the carried person image has.
  agex::PersonSegmentation<pcl::PointXYZ> moved;
  moved.setInputCloud (Cloud::Ptr (new Cloud (out.cloud)));
  std::vector<pcl::PointIndices> found_moved;
  moved.segment (found_moved);
  ASSERT_EQ (found_moved.size (), 1u);
  EXPECT_TRUE (moved.getFloorFound ());
  EXPECT_NEAR (moved.getPersons ()[0].distance, 4.0, 0.2);
  EXPECT_NEAR (static_cast<double> (found_moved[0].indices.size ()), static_cast<double> (n1), 0.15 * n1);
  const auto visible_in = std::count_if (labels.begin (), labels.end (), [] (const agex::PartLabel &l) { return l.visible; });
  const auto visible_out =
      std::count_if (out.labels.begin (), out.labels.end (), [] (const agex::PartLabel &l) { return l.visible; });
  EXPECT_GE (visible_out, visible_in - 1);
}
