// sensor_stats: the statistics that tell depth sensors apart (agex::DepthFrameStatistics),
// on real frames and on synthetic frames of each sensor model, for fitting the models
// (doc/sensors.md).
//   sensor_stats real NAME [--masked|--segment] FILE...   depth images (.u16, .png) or
//                 PCDs; person masks: --masked, the valid pixels (frames whose background is
//                 zeroed); --segment, the persons agex::PersonSegmentation finds
//   sensor_stats synth SENSOR MOTION.bvh FRAMES [WIDTH HEIGHT]
//   sensor_stats limbs SENSOR [WIDTH HEIGHT]   forearm survival at 1-4 m
//   sensor_stats picture OUT.png REAL_FILE SENSOR MOTION.bvh FRAME [MIN_M MAX_M [NEAR_M FAR_M]]
//                 the real frame beside a synthetic one (person NEAR-FAR m away), 240 px high
#include <agex/filters/person_segmentation.h>
#include <agex/io/frame_io.h>
#include <agex/simulation/depth_frame_statistics.h>
#include <agex/simulation/synthetic_scene.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstring>
#include <iomanip>
#include <iostream>
#include <string>
#include <vector>

namespace
{
/** The person as the sensor should have seen it: `valid` closed over 7x7 (holes along
  * and inside the silhouette become part of it). */
std::vector<std::uint8_t>
closedMask (const std::vector<std::uint8_t> &valid, int w, int h)
{
  cv::Mat m (h, w, CV_8U, const_cast<std::uint8_t *> (valid.data ()));
  cv::Mat closed;
  cv::morphologyEx (m, closed, cv::MORPH_CLOSE, cv::getStructuringElement (cv::MORPH_ELLIPSE, cv::Size (7, 7)));
  return std::vector<std::uint8_t> (closed.datastart, closed.dataend);
}

/** "kinect:9" = the kinect with a 9-pixel correlation window. */
int
windowOf (const std::string &name)
{
  const auto colon = name.find (':');
  return colon == std::string::npos ? 1 : std::stoi (name.substr (colon + 1));
}

agex::SynthSensor
sensorNamed (std::string name)
{
  name = name.substr (0, name.find (':'));
  agex::SynthSensor s;
  if (!agex::parseSynthSensor (name, s))
    throw std::runtime_error ("unknown sensor '" + name + "' (expected " + agex::synthSensorNames () + ")");
  return s;
}

int
real (int argc, char **argv)
{
  const std::string name = argv[2];
  bool masked = false, segmented = false;
  agex::DepthFrameStatistics stats;
  for (int a = 3; a < argc; ++a)
  {
    if (std::strcmp (argv[a], "--masked") == 0 || std::strcmp (argv[a], "--segment") == 0)
    {
      (argv[a][2] == 'm' ? masked : segmented) = true;
      continue;
    }
    const agex::Frame frame = agex::loadFrame (argv[a]);
    const int w = static_cast<int> (frame.cloud->width), h = static_cast<int> (frame.cloud->height);
    std::vector<std::uint8_t> mask;
    if (masked)
    {
      std::vector<std::uint8_t> valid (frame.cloud->size ());
      for (std::size_t i = 0; i < valid.size (); ++i)
        valid[i] = std::isfinite (frame.cloud->points[i].z) ? 1 : 0;
      mask = closedMask (valid, w, h);
    }
    else if (segmented)
    {
      agex::PersonSegmentation<pcl::PointXYZ> segmentation;
      segmentation.setInputCloud (frame.cloud);
      std::vector<pcl::PointIndices> persons;
      segmentation.segment (persons);
      std::vector<std::uint8_t> person (frame.cloud->size (), 0);
      for (const auto &p : persons)
        for (const int i : p.indices)
          person[static_cast<std::size_t> (i)] = 1;
      mask = closedMask (person, w, h);
    }
    stats.add (*frame.cloud, mask);
  }
  std::cout << stats.report (name);
  return 0;
}

int
synth (int argc, char **argv)
{
  if (argc < 5)
    throw std::runtime_error ("synth needs SENSOR MOTION.bvh FRAMES");
  agex::SynthOptions options;
  options.sensor = sensorNamed (argv[2]);
  options.motion_files = {argv[3]};
  options.seed = 3;
  const int frames = std::stoi (argv[4]);
  const agex::SynthGenerator gen (options);
  agex::DepthFrameStatistics stats;
  for (int f = 0; f < frames; ++f)
  {
    const agex::SynthFrame frame = gen.render (static_cast<std::uint64_t> (f));
    const int w = static_cast<int> (frame.cloud.width), h = static_cast<int> (frame.cloud.height);
    std::vector<std::uint8_t> person (frame.cloud.size ());
    for (std::size_t i = 0; i < person.size (); ++i)
      person[i] = frame.person_label[i] != 0;
    stats.add (frame.cloud, closedMask (person, w, h));
  }
  std::cout << stats.report (std::string ("synthetic-") + argv[2]);
  return 0;
}

/** Pixels of a forearm (a capsule 7 cm across, 25 cm long, across the view) with a depth on
  * it, over the pixels whose centre ray hits it, before a wall 1 m behind it. */
int
limbs (int argc, char **argv)
{
  agex::SensorModel model = agex::renderSensorModel (sensorNamed (argv[2]));
  model.kinect_window = windowOf (argv[2]);
  if (argc >= 5)
    model = agex::scaledTo (model, std::stoi (argv[3]), std::stoi (argv[4]));
  std::cout << "forearm survival, " << argv[2] << " " << model.width << "x" << model.height << ":";
  for (const double z : {1.0, 2.0, 3.0, 4.0})
  {
    std::size_t ideal = 0, kept = 0;
    for (int trial = 0; trial < 8; ++trial)
    {
      agex::SynthScene scene;
      const double angle = 0.3 * trial;  // forearms in several directions
      const Eigen::Vector3d c (0.02 * trial, -0.03 * trial, z), d (std::cos (angle), std::sin (angle), 0.0);
      scene.primitives.push_back (agex::SynthPrimitive::capsule (c - 0.125 * d, c + 0.125 * d, 0.035,
                                                                 agex::SynthObject::Person));
      scene.primitives.push_back (
          agex::SynthPrimitive::plane (Eigen::Vector3d (0, 0, 1), z + 1.0, agex::SynthObject::Wall));
      agex::SynthRng rng (static_cast<std::uint64_t> (trial) + 1);
      agex::SynthFrame frame;
      agex::renderScene (scene, model, rng, frame);
      for (std::size_t i = 0; i < frame.primitive.size (); ++i)
      {
        const bool on_arm = frame.primitive[i] == 0;
        ideal += on_arm;
        const float zi = frame.cloud.points[i].z;
        kept += on_arm && std::isfinite (zi) && std::abs (zi - z) < 0.15;
      }
    }
    std::cout << " " << z << "m " << std::fixed << std::setprecision (2)
              << (ideal ? static_cast<double> (kept) / ideal : 0.0) << " (" << ideal << " px)";
    std::cout.unsetf (std::ios::fixed);
  }
  std::cout << "\n";
  return 0;
}
/** Flat walls at 1-6.5 m, turned up to 50 degrees, through a sensor with disparity noise
  * sigma_q (kinect) : what the flat-surface noise would be with that setting. */
int
walls (int argc, char **argv)
{
  agex::SensorModel model = agex::renderSensorModel (sensorNamed (argv[2]));
  model.kinect_window = windowOf (argv[2]);
  if (argc > 3)
    model.kinect_sigma_q = std::stod (argv[3]);
  agex::DepthFrameStatistics stats;
  agex::SynthRng rng (5);
  for (double z = 1.0; z < 6.6; z += 0.25)
    for (int k = 0; k < 3; ++k)
    {
      const double yaw = rng.uniform (-0.9, 0.9), pitch = rng.uniform (-0.7, 0.7);
      const Eigen::Vector3d n (std::sin (yaw) * std::cos (pitch), std::sin (pitch), std::cos (yaw) * std::cos (pitch));
      agex::SynthScene scene;
      scene.primitives.push_back (agex::SynthPrimitive::plane (n, n.z () * z, agex::SynthObject::Wall));
      agex::SynthFrame frame;
      agex::renderScene (scene, model, rng, frame);
      stats.add (frame.cloud);
    }
  std::cout << stats.report (std::string ("walls-") + argv[2] + "-sigma_q" + (argc > 3 ? argv[3] : "default"));
  return 0;
}

/** Depth coloured from near (blue) to far (red) over [lo, hi] metres, no depth black,
  * scaled to 240 pixels high. */
cv::Mat
colourDepth (const pcl::PointCloud<pcl::PointXYZ> &cloud, double lo, double hi)
{
  cv::Mat grey (static_cast<int> (cloud.height), static_cast<int> (cloud.width), CV_8U, cv::Scalar (0));
  cv::Mat valid = grey.clone ();
  for (int v = 0; v < grey.rows; ++v)
    for (int u = 0; u < grey.cols; ++u)
    {
      const float z = cloud (u, v).z;
      if (!std::isfinite (z))
        continue;
      grey.at<std::uint8_t> (v, u) = cv::saturate_cast<std::uint8_t> (255.0 * (z - lo) / (hi - lo));
      valid.at<std::uint8_t> (v, u) = 255;
    }
  cv::Mat colour;
  cv::applyColorMap (grey, colour, cv::COLORMAP_JET);
  colour.setTo (cv::Scalar (0, 0, 0), valid == 0);
  cv::Mat out;
  cv::resize (colour, out, cv::Size (colour.cols * 240 / colour.rows, 240), 0, 0, cv::INTER_NEAREST);
  return out;
}

int
picture (int argc, char **argv)
{
  if (argc < 7)
    throw std::runtime_error ("picture needs OUT.png REAL_FILE SENSOR MOTION.bvh FRAME");
  const double lo = argc > 8 ? std::stod (argv[7]) : 0.5, hi = argc > 8 ? std::stod (argv[8]) : 4.5;
  const agex::Frame real = agex::loadFrame (argv[3]);
  agex::SynthOptions options;
  options.sensor = sensorNamed (argv[4]);
  options.motion_files = {argv[5]};
  options.seed = 3;
  if (argc > 10)  // the synthetic person's distance, to match the real frame's
  {
    options.min_distance = std::stod (argv[9]);
    options.max_distance = std::stod (argv[10]);
  }
  const agex::SynthGenerator gen (options);
  const agex::SynthFrame frame = gen.render (static_cast<std::uint64_t> (std::stoi (argv[6])));
  cv::Mat both;
  cv::hconcat (colourDepth (*real.cloud, lo, hi), colourDepth (frame.cloud, lo, hi), both);
  if (!cv::imwrite (argv[2], both))
    throw std::runtime_error (std::string ("cannot write ") + argv[2]);
  return 0;
}
}  // namespace

int
main (int argc, char **argv)
{
  try
  {
    const std::string mode = argc > 1 ? argv[1] : "";
    if (mode == "real" && argc >= 4)
      return real (argc, argv);
    if (mode == "synth")
      return synth (argc, argv);
    if (mode == "limbs" && argc >= 3)
      return limbs (argc, argv);
    if (mode == "walls" && argc >= 3)
      return walls (argc, argv);
    if (mode == "picture")
      return picture (argc, argv);
    std::cerr << "usage: sensor_stats real NAME [--masked] FILE... | synth SENSOR MOTION.bvh FRAMES | "
                 "limbs SENSOR [WIDTH HEIGHT]\n";
    return 2;
  }
  catch (const std::exception &e)
  {
    std::cerr << "sensor_stats: " << e.what () << "\n";
    return 1;
  }
}
