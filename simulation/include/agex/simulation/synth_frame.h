#pragma once
// A rendered synthetic frame: the sensor's cloud, its labels and the per-pixel ground truth.
#include <agex/io/dataset.h>
#include <agex/simulation/scene_primitives.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <array>
#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace agex
{
/** How a label's visibility was decided (parallel to SynthFrame::labels). */
struct SynthLabelCheck
{
  std::vector<int> primitives;  ///< scene primitives of the tip's part
  double tolerance = 0.05;      ///< metres
};

/** Where one person of a scene with several (SynthOptions::people > 1) stands and
  * what they do. The camera stands on the floor plan's origin and looks along its view
  * direction (before the aim's jitter). */
struct SynthPersonPlacement
{
  int clip = 0, clip_frame = 0, subject = 0;
  double distance = 2.0;  ///< horizontal, camera to the middle of the torso, metres
  double bearing = 0.0;   ///< radians from the view direction, positive to the image's right
  double facing = 0.0;    ///< the body's turn about the vertical, radians
};

/** A rendered frame, in the camera frame (x right, y down, z forward, metres). */
struct SynthFrame
{
  pcl::PointCloud<pcl::PointXYZ> cloud;  ///< organized, NaN = invalid (the sensor output)
  std::vector<PartLabel> labels;         ///< head, hands, feet (frame id left empty)
  std::vector<SynthLabelCheck> label_checks;  ///< parallel to labels
  // Ground truth per pixel (row-major), noise free:
  std::vector<SynthObject> object;  ///< what most of the pixel's samples hit
  std::vector<int> primitive;       ///< scene primitive seen at the pixel centre, -1 if none
  std::vector<float> ideal_z;       ///< depth at the pixel centre, NaN if nothing
  std::vector<float> sample_min_z, sample_max_z;  ///< over the pixel's samples (NaN if none hit)
  /** Depth the sensor measured before its noise, shadows and holes: sr4000, that of the
    * amplitude-weighted blend of the samples' ranges (along the centre ray); kinect, the
    * centre ray's. NaN where it measured nothing. */
  std::vector<float> clean_z;
  /** Per pixel: the SynthPart of the body surface the pixel's depth shows, 0 for the
    * room, nothing, or no valid depth (doc/synthetic.md, "Part labels"). */
  std::vector<std::uint8_t> part_label;
  /** Per pixel: the person (SynthPrimitive::person, 1, 2, ...) of that surface; 0 where
    * part_label is 0. */
  std::vector<std::uint8_t> person_label;
  /** Colour image (row-major r, g, b), filled by shadeColour; empty for depth-only frames. */
  std::vector<std::array<std::uint8_t, 3>> colour;
  SynthScene scene;                 ///< the scene in the camera frame
  Eigen::Isometry3d world_to_camera = Eigen::Isometry3d::Identity ();
  // What was drawn (for several people: those of person 1, the nearest):
  int clip = 0, clip_frame = 0, subject = 0;
  std::string sequence;
  /** Several people: person k + 1 stands at people[k], nearest first; empty for one. */
  std::vector<SynthPersonPlacement> people;
};
}  // namespace agex
