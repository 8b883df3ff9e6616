#include <agex/simulation/dataset_reprojection.h>

#include <agex/common/statistics.h>
#include <agex/simulation/synth_rng.h>

#include <chrono>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>

namespace agex
{
namespace
{
void
checkOption (double value, double lo, double hi, const std::string &name)
{
  if (!(value >= lo && value <= hi))
    throw std::invalid_argument ("dataset re-projection: " + name + " " + std::to_string (value) + " is outside " +
                                 std::to_string (lo) + " to " + std::to_string (hi));
}
}  // namespace

void
DatasetReprojectionOptions::validate () const
{
  if (!(min_distance == 0.0 && max_distance == 0.0))
  {
    checkOption (min_distance, 0.3, 20.0, "min_distance (metres)");
    checkOption (max_distance, min_distance, 20.0, "max_distance (metres, at least min_distance)");
  }
  checkOption (sideways, 0.0, 10.0, "sideways (metres)");
  checkOption (vertical, 0.0, 10.0, "vertical (metres)");
  checkOption (tilt_deg, 0.0, 80.0, "tilt_deg (degrees)");
  checkOption (copies, 1, 1000, "copies");
  checkOption (label_tolerance, 0.001, 1.0, "label_tolerance (metres)");
  mesh.validate ();
  FrameReprojection check;
  check.setTargetSensor (sensor);
}

double
depthQuantumOf (const DatasetInfo &info)
{
  return info.depth_scale > 0.0 && info.depth_scale <= 0.05 ? info.depth_scale : 0.0;
}

ReprojectionMove
drawReprojectionMove (const DatasetReprojectionOptions &options, std::uint64_t item, double person_depth,
                      std::uint64_t *noise_seed)
{
  SynthRng rng = SynthRng::forItem (options.seed, item);
  // Always the same draws in the same order, so that one option does not change the others'.
  const double distance = rng.uniform (options.min_distance, options.max_distance);
  ReprojectionMove move;
  move.dx = rng.uniform (-options.sideways, options.sideways);
  move.dy = rng.uniform (-options.vertical, options.vertical);
  move.tilt_deg = rng.uniform (-options.tilt_deg, options.tilt_deg);
  if (options.max_distance > 0.0 && std::isfinite (person_depth))
    move.dz = distance - person_depth;
  const std::uint64_t noise = rng.raw ();
  if (noise_seed)
    *noise_seed = noise;
  return move;
}

DatasetInfo
reprojectedDatasetInfo (const Dataset &input, const DatasetReprojectionOptions &options)
{
  const DatasetInfo &in = input.info ();
  DatasetInfo info;
  info.name = in.name + "-reprojected-" + synthSensorName (options.sensor.sensor);
  info.sensor = synthSensorName (options.sensor.sensor);
  info.width = options.sensor.width;
  info.height = options.sensor.height;
  info.intrinsics = options.sensor.intrinsics;
  info.depth_scale = options.sensor.sensor == SynthSensor::Bonn && options.bonn_depth_levels ? kBonnDepthStep : 1.0;
  info.units = "m";
  info.part_labels = in.part_labels;
  info.person_labels = in.person_labels;
  std::ostringstream p;
  p << "agex_reproject: frames of " << input.directory () << " (" << in.name << ", " << in.width << "x" << in.height
    << ") meshed (joined within " << options.mesh.gap_steps << " depth steps of max(" << options.mesh.depth_quantum
    << ", " << options.mesh.depth_step_growth << " z^2) m plus " << options.mesh.gap_slope
    << " x the pixel spacing), " << options.copies << " copies each moved by";
  if (options.max_distance > 0.0)
    p << " a person median depth of " << options.min_distance << "-" << options.max_distance << " m,";
  p << " +-" << options.sideways << " m sideways, +-" << options.vertical << " m vertically, camera tilt +-"
    << options.tilt_deg << " deg, rendered and measured by the " << synthSensorName (options.sensor.sensor)
    << " sensor model (" << info.width << "x" << info.height << ", fx " << info.intrinsics.fx << ")";
  if (options.sensor.sensor == SynthSensor::Bonn)
    p << (options.bonn_depth_levels ? " in 8-bit depth levels" : " with the kinect's depth (no 8-bit levels)");
  p << (options.find_floor ? "; each frame's floor (where found) rendered as a plane beyond what the frame shows"
                           : "; only what the frames show (no floor added)");
  p << "; seed " << options.seed << "; labels hidden when something is nearer than "
    << options.label_tolerance << " m in front of them (doc/apps/agex_reproject.md); source provenance: "
    << in.provenance;
  info.provenance = p.str ();
  return info;
}

DatasetReprojectionStats
writeReprojectedDataset (const Dataset &input, const std::vector<std::string> &frame_ids,
                         const DatasetReprojectionOptions &options, const std::string &output, bool overwrite,
                         const std::function<void (std::size_t, std::size_t)> &progress)
{
  options.validate ();
  std::map<std::string, std::size_t> position;
  for (std::size_t i = 0; i < input.frames ().size (); ++i)
    position[input.frames ()[i].id] = i;

  DatasetReprojectionStats stats;
  DatasetWriter writer (output, reprojectedDatasetInfo (input, options), overwrite);
  FrameReprojection reprojection;
  reprojection.setMeshSettings (options.mesh);
  reprojection.setTargetSensor (options.sensor);
  reprojection.setBonnDepthLevels (options.bonn_depth_levels);
  reprojection.setLabelTolerance (options.label_tolerance);
  for (std::size_t f = 0; f < frame_ids.size (); ++f)
  {
    const std::string &id = frame_ids[f];
    const auto found = position.find (id);
    if (found == position.end ())
      throw std::invalid_argument ("dataset re-projection: " + input.directory () + " has no frame '" + id + "'");
    ++stats.frames_in;
    const FrameReprojection::Cloud::Ptr cloud = input.loadFrame (id);
    const std::vector<PartLabel> labels = input.labelsOf (id);
    const cv::Mat persons = input.hasPersonLabels () ? input.loadPersonLabels (id) : cv::Mat ();
    const cv::Mat parts = input.hasPartLabels () ? input.loadPartLabels (id) : cv::Mat ();
    const double depth = FrameReprojection::personMedianDepth (*cloud, labels, persons);
    if (options.max_distance > 0.0 && !std::isfinite (depth))
    {
      ++stats.skipped;
      if (progress)
        progress (f + 1, frame_ids.size ());
      continue;
    }
    Eigen::Vector4f floor;
    if (options.find_floor && options.find_floor (*cloud, floor))
    {
      reprojection.setFloorPlane (floor);
      ++stats.with_floor;
    }
    else
      reprojection.clearFloorPlane ();
    reprojection.setInputCloud (cloud);
    reprojection.setLabels (labels);
    reprojection.setPersonImage (persons);
    reprojection.setPartImage (parts);
    const std::string sequence = input.frames ()[found->second].sequence;
    for (int copy = 0; copy < options.copies; ++copy)
    {
      std::uint64_t noise_seed = 0;
      const std::uint64_t item = static_cast<std::uint64_t> (found->second) * static_cast<std::uint64_t> (options.copies) +
                                 static_cast<std::uint64_t> (copy);
      reprojection.setMove (drawReprojectionMove (options, item, depth, &noise_seed));
      reprojection.setSeed (noise_seed);
      ReprojectedFrame frame;
      reprojection.compute (frame);
      stats.mesh_ms += frame.mesh_ms;
      stats.render_ms += frame.render_ms;
      const auto start = std::chrono::steady_clock::now ();
      const std::string copy_id = id + "_c" + std::to_string (copy);
      writer.addFrame (copy_id, sequence, frame.cloud, frame.labels);
      if (!frame.persons.empty ())
        writer.addPersonLabels (copy_id, frame.persons);
      if (!frame.parts.empty ())
        writer.addPartLabels (copy_id, frame.parts);
      stats.write_ms += msSince (start);
      ++stats.frames_out;
      stats.labels += frame.labels.size ();
      stats.dropped_labels += frame.dropped_labels;
      for (const PartLabel &label : frame.labels)
        stats.visible_labels += label.visible ? 1 : 0;
    }
    if (progress)
      progress (f + 1, frame_ids.size ());
  }
  if (stats.frames_out == 0)
    throw std::invalid_argument ("dataset re-projection: none of the " + std::to_string (stats.frames_in) + " frames of " +
                                 input.directory () + " has a person depth (a person image or a labelled 3D point) "
                                 "to move to a distance; nothing written");
  const auto start = std::chrono::steady_clock::now ();
  writer.commit ();
  stats.write_ms += msSince (start);
  return stats;
}
}  // namespace agex
