#pragma once
// Sensor models of the synthetic frames (doc/synthetic.md, "Sensor models"; the fit to
// real frames in doc/sensors.md): which sensor, its image and the parameters of how it
// turns the renderer's ideal ray hits into measured depth. The models themselves are
// classes deriving from agex::DepthSensor (depth_sensor.h), one file each.

#include <agex/io/frame_io.h>

#include <string>

namespace agex
{
enum class SynthSensor
{
  Sr4000,
  Kinect,
  Bonn,    ///< the Bonn frames' look: kinect, 8-bit depth in 1.6 cm steps, their 144x176 portrait view
  Kinect2  ///< Kinect v2-like time of flight, 512x424
};

/** "sr4000", "kinect", "bonn" or "kinect2". */
const char *synthSensorName (SynthSensor sensor);
/** Inverse of synthSensorName ("kinect1" is also taken for kinect); false for an unknown name. */
bool parseSynthSensor (const std::string &name, SynthSensor &sensor);
/** The names parseSynthSensor takes, "sr4000, kinect, kinect2 or bonn", for messages. */
std::string synthSensorNames ();

/** The image a sensor model produces and its noise parameters (doc/synthetic.md). The
  * bonn model's image is the 144x176 portrait view (bonnPortraitView) of a kinect
  * frame; it is rendered with renderSensorModel(Bonn), the kinect model. */
struct SensorModel
{
  SynthSensor sensor = SynthSensor::Sr4000;
  int width = 144, height = 176;
  CameraIntrinsics intrinsics;
  int supersample = 3;           ///< samples per pixel side (time of flight: blended)
  double min_range = 0.1, max_range = 5.0;  ///< metres; outside -> NaN
  // Time of flight (sr4000, kinect2): sigma = tof_sigma0 + tof_sigma_k / amplitude, with
  // amplitude = reflectivity * cos(incidence) / range^2 averaged over the samples.
  double tof_sigma0 = 0.001, tof_sigma_k = 0.0008, tof_sigma_max = 0.05;
  double tof_min_amplitude = 0.008;  ///< below: NaN (the sensor's confidence cut)
  // kinect (structured light): disparity in 1/8 px, q = 8 * f_ir * b / z, with
  // noise sigma_q, rounded; z = 8 f_ir b / q. Projector at +b along x. f_ir is the IR
  // camera's (the matcher's) focal length: it does not change with the output size.
  double kinect_f_ir = 580.0, kinect_baseline = 0.075, kinect_sigma_q = 0.5;
  double kinect_min_cos = 0.12;       ///< incidence flatter than this: NaN
  double kinect_edge_drop = 0.6;      ///< NaN chance of a pixel at a depth edge
  double kinect_edge_drop_near = 0.2; ///< ... of a pixel beside one
  /** Side of the block-matching (correlation) window in output pixels, odd; 1 = off.
    * A pixel takes the disparity of the surface that dominates its window, so thin
    * limbs thin out or vanish far away and silhouettes round off (KinectV1Sensor). */
  int kinect_window = 1;
  /** Weight of nearer (brighter, better textured) surfaces in the window against farther
    * ones: above 1 silhouettes grow into the background. */
  double kinect_foreground_weight = 1.0;
  /** A pixel whose own surface has less than this share of its window takes the
    * window's dominant surface (or none, if no surface dominates). */
  double kinect_min_support = 0.5;
};

/** The model of a sensor with its default parameters: the frames it writes. */
SensorModel sensorModel (SynthSensor sensor);
/** The model a sensor's frames are rendered with (kinect for bonn, else sensorModel). */
SensorModel renderSensorModel (SynthSensor sensor);
/** \brief The same sensor at another image size: intrinsics scaled (pixel centres kept),
  * the kinect correlation window scaled to the nearest odd size; disparity steps (in the IR
  * camera's pixels) and every metric setting unchanged.
  * \throws std::invalid_argument for a size outside 8-8192 pixels a side */
SensorModel scaledTo (const SensorModel &model, int width, int height);

/** Depth step of the Bonn frames: 8-bit grey levels of 0.016 m (../shared/README.md). */
constexpr double kBonnDepthStep = 0.016;
}  // namespace agex
