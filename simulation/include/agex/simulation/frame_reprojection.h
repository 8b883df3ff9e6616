#pragma once
// Real frames re-projected to other distances (training and test data at distances the
// recordings lack): a real organized depth frame becomes a triangle mesh (depth_frame_mesh.h),
// the mesh is moved rigidly, rendered with the synthetic renderer (renderer.h) and measured by
// a target sensor model (depth_sensor.h), and the frame's tip/base labels move with it.

#include <agex/io/dataset.h>
#include <agex/simulation/depth_frame_mesh.h>
#include <agex/simulation/sensor_model.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <opencv2/core/mat.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace agex
{
/** A rigid move of a frame's scene, in its camera frame (x right, y down, z forward). */
struct ReprojectionMove
{
  /** The scene moves by (dx, dy, dz) metres, each within +-50 ... */
  double dx = 0.0, dy = 0.0, dz = 0.0;
  /** ... then the camera pitches up by this many degrees about its x axis (the scene
    * appears lower in the image), within +-89. */
  double tilt_deg = 0.0;

  /** Old camera coordinates to new: p' = R_x(-tilt) (p + d). */
  Eigen::Isometry3d transform () const;
  /** \throws std::invalid_argument naming the first setting out of range */
  void validate () const;
};

/** A re-projected frame. */
struct ReprojectedFrame
{
  pcl::PointCloud<pcl::PointXYZ> cloud;  ///< organized, the target sensor's size; NaN = invalid
  /** The input's labels moved: visible 0 when hidden (see FrameReprojection::compute). */
  std::vector<PartLabel> labels;
  std::size_t dropped_labels = 0;  ///< labels without a 3D tip or behind the camera: left out
  /** CV_8UC1 of the target size when the input had them (setPersonImage, setPartImage), else
    * empty: what each valid pixel shows (0 where invalid). */
  cv::Mat persons, parts;
  /** Noise-free depth at each pixel centre (row-major, NaN: nothing), the labels' depth test. */
  std::vector<float> ideal_z;
  DepthFrameMeshStats mesh;
  double mesh_ms = 0.0, render_ms = 0.0;
};

/** \brief Re-projects a real depth frame and its labels to another camera pose and sensor.
  *
  * \code
  *   agex::FrameReprojection reprojection;
  *   reprojection.setInputCloud (dataset.loadFrame (id));
  *   reprojection.setLabels (dataset.labelsOf (id));
  *   reprojection.setMove (move);                       // e.g. 1 m farther: move.dz = 1
  *   reprojection.setTargetSensor (agex::sensorModel (agex::SynthSensor::Kinect));
  *   agex::ReprojectedFrame frame;
  *   reprojection.compute (frame);
  * \endcode
  *
  * The frame is meshed (depthFrameScene with setMeshSettings: the source sensor's depth steps
  * decide what is one surface), moved, rendered and measured by the target sensor
  * (renderScene: its quantisation, noise, holes and shadows at the new depths, drawn from
  * setSeed). A bonn target is rendered as a kinect frame and made into the Bonn view
  * (BonnSensor; setBonnDepthLevels). What the frame does not show (behind the person, beyond
  * its field of view) stays empty: moved back, the scene is framed by invalid pixels. Setters
  * throw std::invalid_argument naming a setting out of range.
  */
class FrameReprojection
{
public:
  using Cloud = pcl::PointCloud<pcl::PointXYZ>;

  FrameReprojection ();

  /** The organized frame (metres, camera frame, NaN = invalid; as agex::loadFrame gives). */
  void setInputCloud (const Cloud::ConstPtr &cloud) { input_ = cloud; }
  const Cloud::ConstPtr &getInputCloud () const { return input_; }
  /** The frame's labels (3D tip and base in its camera frame, as agex::Dataset holds them). */
  void setLabels (const std::vector<PartLabel> &labels) { labels_ = labels; }
  const std::vector<PartLabel> &getLabels () const { return labels_; }
  /** Optional per-pixel person and part ids (CV_8UC1, the frame's size; empty: none), carried
    * by the mesh into the output's persons and parts. */
  void setPersonImage (const cv::Mat &persons) { persons_ = persons; }
  void setPartImage (const cv::Mat &parts) { parts_ = parts; }

  void setMeshSettings (const DepthMeshSettings &settings);
  const DepthMeshSettings &getMeshSettings () const { return mesh_; }
  void setMove (const ReprojectionMove &move);
  const ReprojectionMove &getMove () const { return move_; }
  /** The target sensor (sensorModel, scaledTo for another size; exactDepthSensor for none of
    * a sensor's effects). A bonn target must be the Bonn view itself (sensorModel (Bonn)). */
  void setTargetSensor (const SensorModel &model);
  const SensorModel &getTargetSensor () const { return target_; }
  /** Bonn target: store depth in the Bonn frames' 8-bit steps of kBonnDepthStep (default),
    * which end at 4.09 m; false keeps the kinect's depth in the Bonn view. */
  void setBonnDepthLevels (bool on) { bonn_depth_levels_ = on; }
  bool getBonnDepthLevels () const { return bonn_depth_levels_; }
  /** A label is hidden when the noise-free rendered depth at its pixel is nearer than the
    * label by more than this, metres, 0.001-1 (default 0.05, as the synthetic labels). */
  void setLabelTolerance (double metres);
  double getLabelTolerance () const { return label_tolerance_; }
  /** \brief Also renders the frame's floor as an endless plane, in the input's camera frame:
    * n.p + d = height above the floor (as agex::FloorRemoval::getFloorPlane returns it; n
    * normalised here). Moved back, a frame then shows the floor between the camera and the
    * scene and beside it, where the recording saw none, as a camera there would: without it
    * the moved scene floats in an empty frame and a floor finder sees only the patch of floor
    * the recording held. Where the frame's own surfaces are, they show (the plane lies in the
    * recorded floor). \throws std::invalid_argument for a plane without a finite normal */
  void setFloorPlane (const Eigen::Vector4f &plane);
  /** No floor plane (the default): only what the frame shows. */
  void clearFloorPlane () { has_floor_ = false; }
  bool hasFloorPlane () const { return has_floor_; }
  const Eigen::Vector4f &getFloorPlane () const { return floor_; }
  /** The target sensor's noise is drawn from this seed: the same seed gives the same frame. */
  void setSeed (std::uint64_t seed) { seed_ = seed; }
  std::uint64_t getSeed () const { return seed_; }

  /** \brief Meshes, moves, renders and measures the frame; moves the labels.
    *
    * Each label's 3D tip and base move with the scene and are projected with the target's
    * intrinsics (tip_px, base_px). Labels without a finite 3D tip, or whose tip ends behind
    * the camera, cannot be placed and are left out (dropped_labels). A label stays visible
    * only if it was, its tip falls inside the frame and within the sensor's range (for the
    * bonn target with depth levels: up to 255 steps), and the noise-free rendered depth at its
    * pixel is not nearer than the tip by more than the label tolerance (something in front
    * of it); else visible becomes 0 (the dataset format keeps hidden labels).
    *
    * No input cloud, an empty, one-row or all-invalid frame, or a move that leaves the scene
    * behind the camera give a frame of the target's size without a valid pixel.
    * \throws std::invalid_argument for a person or part image of another size or type */
  void compute (ReprojectedFrame &output) const;

  /** \brief The depth a move to a distance is measured on: the median depth of the
    * person's pixels (persons > 0) if a person image is given and shows one, else the
    * median depth of the labels' finite 3D tips and bases; NaN if there is neither. */
  static double personMedianDepth (const Cloud &cloud, const std::vector<PartLabel> &labels,
                                   const cv::Mat &persons = cv::Mat ());

private:
  Cloud::ConstPtr input_;
  std::vector<PartLabel> labels_;
  cv::Mat persons_, parts_;
  DepthMeshSettings mesh_;
  ReprojectionMove move_;
  SensorModel target_;
  bool bonn_depth_levels_ = true;
  double label_tolerance_ = 0.05;
  std::uint64_t seed_ = 1;
  bool has_floor_ = false;
  Eigen::Vector4f floor_ = Eigen::Vector4f::Zero ();
};

/** \brief A sensor that measures the exact depth of each pixel-centre ray: a time-of-flight
  * model without noise, blending, supersampling or amplitude cut, over min_range-max_range
  * metres. For tests, and for re-projections that should add no sensor effects. */
SensorModel exactDepthSensor (int width, int height, const CameraIntrinsics &intrinsics, double min_range = 0.05,
                              double max_range = 50.0);
}  // namespace agex
