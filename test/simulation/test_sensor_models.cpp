// Sensor models (doc/synthetic.md, "Sensor models"; doc/sensors.md): the Kinect v1's
// disparity steps, the time-of-flight sensors' flying pixels and noise, the correlation
// window, ranges, sizes. Analytic scenes only: no ../shared data needed.
#include <agex/simulation/bonn_sensor.h>
#include <agex/simulation/depth_frame_statistics.h>
#include <agex/simulation/kinect_v1_sensor.h>
#include <agex/simulation/sensor_model.h>
#include <agex/simulation/synthetic_scene.h>
#include <agex/simulation/time_of_flight_sensor.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

namespace
{
agex::SynthScene
wallAt (double z, const Eigen::Vector3d &normal = Eigen::Vector3d::UnitZ ())
{
  agex::SynthScene scene;
  const Eigen::Vector3d n = normal.normalized ();
  scene.primitives.push_back (agex::SynthPrimitive::plane (n, n.dot (Eigen::Vector3d (0, 0, z)), agex::SynthObject::Wall));
  return scene;
}

agex::SynthFrame
render (const agex::SynthScene &scene, const agex::SensorModel &model, std::uint64_t seed = 1)
{
  agex::SynthRng rng (seed);
  agex::SynthFrame frame;
  agex::renderScene (scene, model, rng, frame);
  return frame;
}

/** Sorted distinct depths of the valid pixels within 3% of z. */
std::vector<double>
levelsNear (const agex::SynthFrame &frame, double z)
{
  std::set<double> levels;
  for (const auto &p : frame.cloud.points)
    if (std::isfinite (p.z) && std::abs (p.z - z) < 0.03 * z)
      levels.insert (p.z);
  return std::vector<double> (levels.begin (), levels.end ());
}
}  // namespace

// A slanted wall through 1, 2 and 4 m: the depths the Kinect v1 reports are distinct levels
// z^2 / (8 f_ir b) apart (disparity in 1/8 pixel), as KinectV1Sensor::depthStep says.
TEST (SensorModels, KinectV1DepthStepsGrowWithTheSquareOfTheDepth)
{
  agex::SensorModel model = agex::sensorModel (agex::SynthSensor::Kinect);
  const agex::KinectV1Sensor kinect (model);
  double previous = 0.0;
  for (const double z : {1.0, 2.0, 4.0})
  {
    // Turned 60 degrees about the vertical: the depth changes along each row.
    const agex::SynthFrame frame = render (wallAt (z, Eigen::Vector3d (std::sin (1.05), 0.0, std::cos (1.05))), model);
    const std::vector<double> levels = levelsNear (frame, z);
    ASSERT_GE (levels.size (), 4u) << "at " << z << " m";
    std::vector<double> gaps;
    for (std::size_t k = 1; k < levels.size (); ++k)
      gaps.push_back (levels[k] - levels[k - 1]);
    std::nth_element (gaps.begin (), gaps.begin () + gaps.size () / 2, gaps.end ());
    const double gap = gaps[gaps.size () / 2], expected = kinect.depthStep (z);
    EXPECT_NEAR (gap, expected, 0.1 * expected) << "at " << z << " m";
    // Every level is 8 f b / q for an integer q.
    const double fb8 = 8.0 * model.kinect_f_ir * model.kinect_baseline;
    for (const double level : levels)
      EXPECT_NEAR (fb8 / level, std::round (fb8 / level), 2e-3 * fb8 / level);
    EXPECT_GT (gap, 3.5 * previous) << "doubling the depth makes the step about 4 times larger";
    previous = gap;
  }
  EXPECT_NEAR (kinect.depthStep (2.0), 4.0 / (8.0 * 580.0 * 0.075), 1e-9);
}

// A box in front of a wall: time-of-flight pixels on its silhouette measure depths between
// the two (flying pixels); the Kinect v1 has none.
TEST (SensorModels, TimeOfFlightFlyingPixelsAtSilhouettes)
{
  agex::SynthScene scene = wallAt (3.0);
  scene.primitives.push_back (agex::SynthPrimitive::box (Eigen::Vector3d (0.031, 0.017, 1.5),
                                                         Eigen::Matrix3d::Identity () * 0.2, agex::SynthObject::Person));
  for (const agex::SynthSensor sensor : {agex::SynthSensor::Kinect2, agex::SynthSensor::Sr4000, agex::SynthSensor::Kinect})
  {
    const agex::SensorModel model = agex::sensorModel (sensor);
    const agex::SynthFrame frame = render (scene, model);
    std::size_t between = 0, valid = 0;
    for (const auto &p : frame.cloud.points)
      if (std::isfinite (p.z))
      {
        ++valid;
        between += p.z > 1.3 + 0.1 && p.z < 3.0 - 0.1;  // box front at 1.3 m, wall at 3 m
      }
    ASSERT_GT (valid, static_cast<std::size_t> (model.width) * model.height / 2) << agex::synthSensorName (sensor);
    if (sensor == agex::SynthSensor::Kinect)
      EXPECT_EQ (between, 0u) << "structured light has no mixed pixels";
    else
      EXPECT_GT (between, 20u) << agex::synthSensorName (sensor) << ": flying pixels along the box's outline";
  }
  // Kinect v2 at 512x424, fx 365.
  const agex::SensorModel k2 = agex::sensorModel (agex::SynthSensor::Kinect2);
  EXPECT_EQ (k2.width, 512);
  EXPECT_EQ (k2.height, 424);
  EXPECT_NEAR (k2.intrinsics.fx, 365.0, 1.0);
}

// Depth noise on a wall facing the camera grows with its distance as the models say.
TEST (SensorModels, NoiseGrowsWithDistanceAsModelled)
{
  for (const agex::SynthSensor sensor : {agex::SynthSensor::Kinect2, agex::SynthSensor::Kinect})
  {
    const agex::SensorModel model = agex::sensorModel (sensor);
    const agex::TimeOfFlightSensor tof (agex::sensorModel (agex::SynthSensor::Kinect2));
    double previous = 0.0;
    for (const double z : {1.0, 2.0, 3.5})
    {
      const agex::SynthFrame frame = render (wallAt (z), model, 7);
      double sum2 = 0.0;
      std::size_t n = 0;
      // The middle of the image, where the wall is head-on at depth z.
      for (int v = model.height / 2 - 30; v < model.height / 2 + 30; ++v)
      for (int u = model.width / 2 - 30; u < model.width / 2 + 30; ++u)
      {
        const float d = frame.cloud (u, v).z;
        if (!std::isfinite (d))
          continue;
        sum2 += (d - z) * (d - z);
        ++n;
      }
      ASSERT_GT (n, 3000u);
      const double sigma = std::sqrt (sum2 / n);
      if (sensor == agex::SynthSensor::Kinect2)
      {
        // The amplitude is 0.7 / z^2 here (reflectivity 0.7, head-on).
        const double expected = tof.rangeSigma (0.7 / (z * z));
        EXPECT_NEAR (sigma, expected, 0.15 * expected) << z;
      }
      else
      {
        // Disparity noise of sigma_q eighths of a pixel plus rounding: about
        // depthStep (z) * sqrt (sigma_q^2 + 1/12).
        const double expected = agex::KinectV1Sensor (model).depthStep (z) *
                                std::sqrt (model.kinect_sigma_q * model.kinect_sigma_q + 1.0 / 12.0);
        EXPECT_NEAR (sigma, expected, 0.3 * expected) << z;
      }
      EXPECT_GT (sigma, 1.3 * previous) << agex::synthSensorName (sensor) << " at " << z << " m";
      previous = sigma;
    }
  }
}

// Walls nearer than the minimum or beyond the maximum range give NaN, never a depth; the
// depths given lie within the range.
TEST (SensorModels, NaNOutsideTheRange)
{
  for (const agex::SynthSensor sensor :
       {agex::SynthSensor::Sr4000, agex::SynthSensor::Kinect, agex::SynthSensor::Kinect2, agex::SynthSensor::Bonn})
  {
    const agex::SensorModel model = agex::renderSensorModel (sensor), stored = agex::sensorModel (sensor);
    const double far = sensor == agex::SynthSensor::Bonn ? 256 * agex::kBonnDepthStep : model.max_range;
    for (const double z : {0.5 * model.min_range, far + 0.3, far + 5.0, model.min_range + 0.05, far - 0.3})
    {
      agex::SynthFrame frame = render (wallAt (z), model, 3);
      if (sensor == agex::SynthSensor::Bonn)
        agex::toBonnView (model, stored, frame);
      std::size_t valid = 0;
      for (const auto &p : frame.cloud.points)
      {
        ASSERT_EQ (std::isfinite (p.x), std::isfinite (p.z));
        if (!std::isfinite (p.z))
          continue;
        ++valid;
        ASSERT_GE (p.z, model.min_range * 0.99) << agex::synthSensorName (sensor);
        // Time of flight limits the range along the ray, structured light the depth.
        const bool tof = sensor == agex::SynthSensor::Sr4000 || sensor == agex::SynthSensor::Kinect2;
        ASSERT_LE (tof ? std::sqrt (p.x * p.x + p.y * p.y + p.z * p.z) : p.z, far * 1.001)
            << agex::synthSensorName (sensor);
      }
      const bool inside = z > model.min_range && z < far;
      if (inside)
        EXPECT_GT (valid, frame.cloud.size () / 4) << agex::synthSensorName (sensor) << " at " << z << " m";
      else
        EXPECT_EQ (valid, 0u) << agex::synthSensorName (sensor) << " at " << z << " m";
    }
  }
}

// The correlation window: a bar 2 cm wide at 4 m (2.6 pixels) vanishes into the wall
// behind it, which a 1-pixel window keeps; a forearm 7 cm across at 2 m survives.
TEST (SensorModels, KinectV1CorrelationWindowLosesThinBarsFarAway)
{
  agex::SensorModel model = agex::sensorModel (agex::SynthSensor::Kinect);
  model.kinect_window = 9;  // the fitted window (doc/sensors.md); off by default
  model.kinect_edge_drop = model.kinect_edge_drop_near = 0.0;
  auto kept = [&] (const agex::SensorModel &m, double z, double half_width) {
    agex::SynthScene scene = wallAt (z + 1.0);
    scene.primitives.push_back (agex::SynthPrimitive::box (
        Eigen::Vector3d (0, 0, z), Eigen::Matrix3d (Eigen::Vector3d (half_width, 0.3, half_width).asDiagonal ()), agex::SynthObject::Person));
    const agex::SynthFrame frame = render (scene, m);
    std::size_t on = 0, seen = 0;
    for (std::size_t i = 0; i < frame.primitive.size (); ++i)
      if (frame.primitive[i] == 1)
      {
        ++on;
        seen += std::isfinite (frame.cloud.points[i].z) && std::abs (frame.cloud.points[i].z - (z - half_width)) < 0.2;
      }
    EXPECT_GT (on, 0u);
    return on ? static_cast<double> (seen) / on : 0.0;
  };
  agex::SensorModel no_window = model;
  no_window.kinect_window = 1;
  EXPECT_GT (kept (no_window, 4.0, 0.01), 0.5);
  EXPECT_LT (kept (model, 4.0, 0.01), 0.2);
  EXPECT_GT (kept (model, 2.0, 0.035), 0.7);
}

// 320x240: intrinsics halved, pixel centres kept, window scaled to an odd size; bad sizes
// and settings refused.
TEST (SensorModels, ScaledToAnotherImageSize)
{
  agex::SensorModel vga = agex::sensorModel (agex::SynthSensor::Kinect);
  vga.kinect_window = 9;
  const agex::SensorModel qvga = agex::scaledTo (vga, 320, 240);
  EXPECT_EQ (qvga.width, 320);
  EXPECT_EQ (qvga.height, 240);
  EXPECT_DOUBLE_EQ (qvga.intrinsics.fx, 262.5);
  EXPECT_DOUBLE_EQ (qvga.intrinsics.cx, 159.5);
  EXPECT_DOUBLE_EQ (qvga.intrinsics.cy, 119.5);
  EXPECT_EQ (qvga.kinect_window % 2, 1);
  EXPECT_LT (qvga.kinect_window, vga.kinect_window);
  EXPECT_EQ (qvga.kinect_f_ir, vga.kinect_f_ir) << "disparity steps are the IR camera's";
  const agex::SynthFrame frame = render (wallAt (2.0), qvga);
  EXPECT_EQ (frame.cloud.width, 320u);
  EXPECT_THROW (agex::scaledTo (vga, 0, 240), std::invalid_argument);
  agex::SensorModel bad = vga;
  bad.kinect_window = 4;
  agex::SynthRng rng (1);
  agex::SynthFrame out;
  EXPECT_THROW (agex::renderScene (wallAt (2.0), bad, rng, out), std::invalid_argument);
  agex::SynthSensor s;
  EXPECT_TRUE (agex::parseSynthSensor ("kinect2", s));
  EXPECT_EQ (s, agex::SynthSensor::Kinect2);
  EXPECT_FALSE (agex::parseSynthSensor ("kinect3", s));
}

// The statistics see what the models make: the Kinect v1's steps, fitted back to its 8 f b,
// and ToF flying pixels at a mask's edge but none from the Kinect v1.
TEST (SensorModels, DepthFrameStatisticsMeasureTheModels)
{
  agex::SensorModel kinect = agex::sensorModel (agex::SynthSensor::Kinect);
  agex::DepthFrameStatistics steps;
  for (const double z : {1.0, 2.0, 3.0, 4.0})
    steps.add (render (wallAt (z, Eigen::Vector3d (std::sin (1.05), 0.0, std::cos (1.05))), kinect).cloud);
  EXPECT_NEAR (steps.fittedDisparityConstant (), 8.0 * kinect.kinect_f_ir * kinect.kinect_baseline, 25.0);

  agex::SynthScene scene = wallAt (3.0);
  scene.primitives.push_back (agex::SynthPrimitive::box (Eigen::Vector3d (0.031, 0.017, 1.5),
                                                         Eigen::Matrix3d::Identity () * 0.2, agex::SynthObject::Person));
  double flying[2] = {0, 0};
  for (const agex::SynthSensor sensor : {agex::SynthSensor::Kinect2, agex::SynthSensor::Kinect})
  {
    const agex::SynthFrame frame = render (scene, agex::sensorModel (sensor));
    std::vector<std::uint8_t> mask (frame.object.size ());
    for (std::size_t i = 0; i < mask.size (); ++i)
      mask[i] = frame.object[i] == agex::SynthObject::Person;
    agex::DepthFrameStatistics stats;
    stats.add (frame.cloud, mask);
    flying[sensor == agex::SynthSensor::Kinect] = stats.silhouetteFlyingRate ();
    EXPECT_GT (stats.silhouetteSteps (), 40u) << "most edge pixels are holes for the kinect";
  }
  EXPECT_GT (flying[0], 0.02);
  EXPECT_LT (flying[1], 0.005);
  EXPECT_THROW (agex::DepthFrameStatistics ().add (render (wallAt (2.0), kinect).cloud, std::vector<std::uint8_t> (3)),
                std::invalid_argument);
}
