#pragma once
// A dataset's frames re-projected to other distances, sensors and camera poses
// (FrameReprojection, frame_reprojection.h), each frame in several randomly moved copies,
// written as a new agex dataset (agex_reproject).

#include <agex/io/dataset.h>
#include <agex/simulation/frame_reprojection.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace agex
{
/** How each copy of a frame is moved and measured. */
struct DatasetReprojectionOptions
{
  /** The target sensor (sensorModel, scaledTo); bonn: the Bonn view (bonn_depth_levels). */
  SensorModel sensor = sensorModel (SynthSensor::Kinect);
  bool bonn_depth_levels = true;
  /** The person's median depth after the move (FrameReprojection::personMedianDepth, before
    * the tilt), metres, drawn uniformly per copy from [min_distance, max_distance], 0.3-20;
    * both 0: the depth is left as it is. */
  double min_distance = 0.0, max_distance = 0.0;
  /** Each copy moves sideways (x) by up to +-sideways and vertically (y) by up to
    * +-vertical metres (0-10), and the camera tilts by up to +-tilt_deg degrees (0-80);
    * each drawn uniformly. */
  double sideways = 0.0, vertical = 0.0, tilt_deg = 0.0;
  int copies = 1;  ///< per frame, 1-1000
  std::uint64_t seed = 1;
  /** The source frames' surfaces (depthQuantumOf gives the quantum of a dataset's frames). */
  DepthMeshSettings mesh;
  double label_tolerance = 0.05;  ///< metres (FrameReprojection::setLabelTolerance)
  /** Finds a frame's floor (n.p + d = height above it, FrameReprojection::setFloorPlane);
    * false for none. Empty (the default): no floor plane, only what the frames show.
    * agex_reproject passes agex::PersonSegmentation's floor (a module this one does not link). */
  std::function<bool (const pcl::PointCloud<pcl::PointXYZ> &cloud, Eigen::Vector4f &plane)> find_floor;

  /** \throws std::invalid_argument naming the first setting out of range */
  void validate () const;
};

/** \brief The fixed depth step of a dataset's frames for DepthMeshSettings::depth_quantum: its
  * depth_scale when that is a step of stored depth (0 < scale <= 0.05 m: 0.016 for the
  * Bonn frames' 8-bit levels, 0.001 for millimetres), else 0 (metric clouds, synthetic
  * datasets' 1). */
double depthQuantumOf (const DatasetInfo &info);

/** \brief The move of one copy: drawn from (seed, item) where item = frame's position in the
  * dataset x copies + copy; dz brings person_depth to the drawn distance (0 without one, or
  * when person_depth is not finite). */
ReprojectionMove drawReprojectionMove (const DatasetReprojectionOptions &options, std::uint64_t item,
                                       double person_depth, std::uint64_t *noise_seed = nullptr);

/** What writeReprojectedDataset did. */
struct DatasetReprojectionStats
{
  std::size_t frames_in = 0, frames_out = 0;
  /** Frames left out: a distance was asked for but the frame has no person depth (neither a
    * person image nor a labelled 3D point). */
  std::size_t skipped = 0;
  std::size_t labels = 0, visible_labels = 0, dropped_labels = 0;
  std::size_t with_floor = 0;  ///< input frames whose floor was found and rendered (find_floor)
  double mesh_ms = 0.0, render_ms = 0.0, write_ms = 0.0;  ///< totals over the copies
};

/** The new dataset's description: the target's name, size and intrinsics, the input's part
  * labels and person labels, and a provenance naming the input and the options. */
DatasetInfo reprojectedDatasetInfo (const Dataset &input, const DatasetReprojectionOptions &options);

/** \brief Re-projects the given frames of input (ids of it, in order), `copies` per frame
  * with ids "<id>_c<k>" in the frame's sequence, with the input's person and part images when
  * it has them, and writes them as an agex dataset atomically (DatasetWriter: staged beside
  * output, renamed into place at the end). progress (done, total) after each frame.
  * \throws std::invalid_argument for bad options or when a distance is asked for and no frame
  *         has a person depth (nothing is written), DatasetError as DatasetWriter, FrameError
  *         naming a bad frame */
DatasetReprojectionStats writeReprojectedDataset (const Dataset &input, const std::vector<std::string> &frame_ids,
                                                  const DatasetReprojectionOptions &options, const std::string &output,
                                                  bool overwrite,
                                                  const std::function<void (std::size_t, std::size_t)> &progress = {});
}  // namespace agex
