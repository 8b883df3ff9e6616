#include <agex/simulation/frame_reprojection.h>

#include <agex/common/statistics.h>
#include <agex/simulation/bonn_sensor.h>
#include <agex/simulation/depth_sensor.h>
#include <agex/simulation/synth_rng.h>
#include <agex/simulation/synthetic_scene.h>

#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace agex
{
namespace
{
constexpr double kPi = 3.14159265358979323846;

void
checkSetting (double value, double lo, double hi, const std::string &name)
{
  if (!(value >= lo && value <= hi))
    throw std::invalid_argument ("FrameReprojection: " + name + " " + std::to_string (value) + " is outside " +
                                 std::to_string (lo) + " to " + std::to_string (hi));
}

Eigen::Vector2f
project (const CameraIntrinsics &k, const Eigen::Vector3d &p)
{
  return Eigen::Vector2f (static_cast<float> (k.fx * p.x () / p.z () + k.cx),
                          static_cast<float> (k.fy * p.y () / p.z () + k.cy));
}

/** A per-pixel label vector as an image, keeping only the ids the input image had (the
  * renderer calls a body pixel without a part Unknown, which the input may not name). */
cv::Mat
labelImage (const std::vector<std::uint8_t> &labels, int width, int height, const cv::Mat &input)
{
  std::array<bool, 256> known{};
  for (int r = 0; r < input.rows; ++r)
    for (int c = 0; c < input.cols; ++c)
      known[input.at<std::uint8_t> (r, c)] = true;
  cv::Mat image (height, width, CV_8UC1, cv::Scalar (0));
  for (std::size_t i = 0; i < labels.size () && i < image.total (); ++i)
    image.data[i] = known[labels[i]] ? labels[i] : 0;
  return image;
}
}  // namespace

Eigen::Isometry3d
ReprojectionMove::transform () const
{
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity ();
  t.linear () = Eigen::AngleAxisd (-tilt_deg * kPi / 180.0, Eigen::Vector3d::UnitX ()).toRotationMatrix ();
  t.translation () = t.linear () * Eigen::Vector3d (dx, dy, dz);
  return t;
}

void
ReprojectionMove::validate () const
{
  checkSetting (dx, -50.0, 50.0, "move dx (metres)");
  checkSetting (dy, -50.0, 50.0, "move dy (metres)");
  checkSetting (dz, -50.0, 50.0, "move dz (metres)");
  checkSetting (tilt_deg, -89.0, 89.0, "tilt (degrees)");
}

FrameReprojection::FrameReprojection () : target_ (sensorModel (SynthSensor::Kinect)) {}

void
FrameReprojection::setMeshSettings (const DepthMeshSettings &settings)
{
  settings.validate ();
  mesh_ = settings;
}

void
FrameReprojection::setMove (const ReprojectionMove &move)
{
  move.validate ();
  move_ = move;
}

void
FrameReprojection::setTargetSensor (const SensorModel &model)
{
  if (model.sensor == SynthSensor::Bonn)
  {
    const SensorModel bonn = sensorModel (SynthSensor::Bonn);
    if (model.width != bonn.width || model.height != bonn.height)
      throw std::invalid_argument ("FrameReprojection: the bonn target sensor's frames are its " +
                                   std::to_string (bonn.width) + "x" + std::to_string (bonn.height) +
                                   " portrait view; no other frame size");
    SensorModel kinect = model;
    kinect.sensor = SynthSensor::Kinect;
    checkSensorModel (kinect);
  }
  else
    checkSensorModel (model);
  target_ = model;
}

void
FrameReprojection::setFloorPlane (const Eigen::Vector4f &plane)
{
  const float norm = plane.head<3> ().norm ();
  if (!plane.allFinite () || !(norm > 1e-6f))
    throw std::invalid_argument ("FrameReprojection: the floor plane needs a finite, non-zero normal and offset");
  floor_ = plane / norm;
  has_floor_ = true;
}

void
FrameReprojection::setLabelTolerance (double metres)
{
  checkSetting (metres, 0.001, 1.0, "label tolerance (metres)");
  label_tolerance_ = metres;
}

void
FrameReprojection::compute (ReprojectedFrame &output) const
{
  output = ReprojectedFrame ();
  const bool bonn = target_.sensor == SynthSensor::Bonn;
  // A bonn target is a kinect frame made into the Bonn view, as agex_synth renders it.
  SensorModel render = target_;
  if (bonn)
  {
    const SensorModel kinect = renderSensorModel (SynthSensor::Bonn);
    render.sensor = SynthSensor::Kinect;
    render.width = kinect.width;
    render.height = kinect.height;
    render.intrinsics = kinect.intrinsics;
  }

  auto start = std::chrono::steady_clock::now ();
  SynthScene scene;
  if (input_)
    scene = depthFrameScene (*input_, mesh_, persons_, parts_, &output.mesh);
  scene = scene.transformed (move_.transform ());
  // The floor goes with a scene the camera sees some of: an empty frame, or one moved behind
  // the camera, stays empty.
  bool in_front = false;
  for (const SynthPrimitive &p : scene.primitives)
  {
    Eigen::Vector3d centre;
    double radius = 0.0;
    in_front = in_front || (p.boundingSphere (centre, radius) && centre.z () + radius > target_.min_range);
  }
  if (has_floor_ && in_front)
    scene.primitives.push_back (
        SynthPrimitive::plane (floor_.head<3> ().cast<double> (), -static_cast<double> (floor_[3]), SynthObject::Floor)
            .transformed (move_.transform ()));
  output.mesh_ms = msSince (start);

  start = std::chrono::steady_clock::now ();
  SynthRng rng (seed_);
  SynthFrame frame;
  renderScene (scene, render, rng, frame);
  if (bonn)
    BonnSensor (render, target_, bonn_depth_levels_).apply (frame);
  output.render_ms = msSince (start);

  const int w = target_.width, h = target_.height;
  output.cloud = std::move (frame.cloud);
  output.ideal_z = std::move (frame.ideal_z);
  if (!persons_.empty ())
    output.persons = labelImage (frame.person_label, w, h, persons_);
  if (!parts_.empty ())
    output.parts = labelImage (frame.part_label, w, h, parts_);

  // The labels move with the scene and are seen (or not) by the target camera.
  const Eigen::Isometry3d move = move_.transform ();
  const CameraIntrinsics &k = target_.intrinsics;
  for (const PartLabel &label : labels_)
  {
    if (!label.tip.allFinite ())
    {
      ++output.dropped_labels;
      continue;
    }
    const Eigen::Vector3d tip = move * label.tip.cast<double> ();
    if (!(tip.z () > 1e-6))
    {
      ++output.dropped_labels;
      continue;
    }
    PartLabel moved = label;
    moved.tip = tip.cast<float> ();
    moved.tip_px = project (k, tip);
    moved.base_px = moved.tip_px;
    if (label.base.allFinite ())
    {
      const Eigen::Vector3d base = move * label.base.cast<double> ();
      moved.base = base.cast<float> ();
      if (base.z () > 1e-6)
        moved.base_px = project (k, base);
    }
    const long u = std::lround (moved.tip_px.x ()), v = std::lround (moved.tip_px.y ());
    bool visible = label.visible && u >= 0 && v >= 0 && u < w && v < h && tip.z () >= target_.min_range &&
                   tip.z () <= target_.max_range && (!bonn || !bonn_depth_levels_ || BonnSensor::depthLevel (tip.z ()) > 0);
    if (visible)
    {
      const float seen = output.ideal_z[static_cast<std::size_t> (v) * w + static_cast<std::size_t> (u)];
      if (std::isfinite (seen) && seen < tip.z () - label_tolerance_)
        visible = false;
    }
    moved.visible = visible;
    output.labels.push_back (moved);
  }
}

double
FrameReprojection::personMedianDepth (const Cloud &cloud, const std::vector<PartLabel> &labels, const cv::Mat &persons)
{
  std::vector<double> depths;
  if (!persons.empty () && persons.type () == CV_8UC1 && persons.total () == cloud.points.size ())
    for (std::size_t i = 0; i < cloud.points.size (); ++i)
      if (persons.data[i] > 0 && std::isfinite (cloud.points[i].z) && cloud.points[i].z > 0.0f)
        depths.push_back (cloud.points[i].z);
  if (depths.empty ())
    for (const PartLabel &label : labels)
      for (const Eigen::Vector3f *p : {&label.tip, &label.base})
        if (p->allFinite () && p->z () > 0.0f)
          depths.push_back (p->z ());
  return median (depths);
}

SensorModel
exactDepthSensor (int width, int height, const CameraIntrinsics &intrinsics, double min_range, double max_range)
{
  SensorModel m = sensorModel (SynthSensor::Sr4000);
  m.width = width;
  m.height = height;
  m.intrinsics = intrinsics;
  m.supersample = 1;
  m.min_range = min_range;
  m.max_range = max_range;
  m.tof_sigma0 = m.tof_sigma_k = m.tof_sigma_max = 0.0;
  m.tof_min_amplitude = 0.0;
  checkSensorModel (m);
  return m;
}
}  // namespace agex
