#pragma once
// Synthetic labelled depth frames (doc/synthetic.md): people (one, or up to four apart,
// partly hiding each other) posed by real motion capture (BVH), a body made of capsules
// and ellipsoids on the skeleton or the MakeHuman mesh, a room
// (floor, back wall, optional side wall, clutter boxes or a desk), a randomly
// placed camera, a ray-casting renderer (renderer.h) and sensor models (sensor_model.h,
// one class each: depth_sensor.h):
//   sr4000   144x176 portrait time-of-flight: 3x3 supersampling whose samples are
//            blended as the sensor blends returns (mixed pixels at silhouettes),
//            range noise growing as the returned amplitude falls (~depth^2)
//   kinect2  512x424 time of flight (Kinect v2-like), the same kind of model
//   kinect   640x480 structured light: disparity quantisation and noise (depth
//            steps grow with depth^2), projector shadows, the correlation window
//            (thin limbs thin out, silhouettes round off) and holes at depth edges
//   bonn     a kinect frame in the Bonn frames' 8-bit depth and 144x176 portrait view
// head / hand / foot tip labels (agex::PartLabel) with a depth-test visibility, and an
// exact per-pixel part label (agex::SynthPart) of the surface each depth pixel shows.
//
// Everything is a function of the seed: frame i draws from its own generator seeded
// from (seed, i), with hand-written uniform and normal variates on std::mt19937_64's
// raw output, so the same seed gives the same bytes on every run and platform with
// the same floating point.

#include <agex/simulation/body_model.h>
#include <agex/simulation/body_shape.h>
#include <agex/simulation/motion_clip.h>
#include <agex/simulation/synth_frame.h>
#include <agex/simulation/synth_labels.h>
#include <agex/simulation/bvh.h>
#include <agex/simulation/scene_primitives.h>
#include <agex/simulation/sensor_model.h>
#include <agex/simulation/synth_rng.h>
#include <agex/io/dataset.h>
#include <agex/io/frame_io.h>
#include <agex/simulation/synth_mesh.h>
#include <agex/simulation/synth_part.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace agex
{
/** \brief Renders a scene (camera frame) with a sensor model; draws the noise from rng.
  * Fills the cloud, the per-pixel ground truth and the part and person labels of the
  * surfaces the depth pixels show: kinect, the surface the pixel-centre ray hits;
  * sr4000, the surface of the pixel's sample nearest to its (noise-free, blended) range,
  * if within 1 cm + 1% of the range of it, else none (a flying pixel between surfaces);
  * none wherever the depth is invalid. */
void renderScene (const SynthScene &scene, const SensorModel &sensor, SynthRng &rng, SynthFrame &frame);

/** \brief Paints a rendered frame as a colour camera would see it (frame.colour), with
  * random appearance so that 2D models trained on it cannot lean on any one look: per
  * frame random skin tone, clothes (top, bottom, shoes), wall, floor and clutter colours,
  * a random light with Lambert shading, faint clothes texture, a strong random pattern on
  * the room's surfaces, a 3x3 blur and pixel noise. Uses the pixel-centre primitives of
  * renderScene; registered with the depth (the colour camera sits at the depth camera).
  * Draws everything from rng, never from the frame's depth noise. */
void shadeColour (const SensorModel &sensor, SynthRng &rng, SynthFrame &frame);

/** How a frame's camera and people are laid out (doc/synthetic.md, "Whole scenes"). */
enum class SynthLayout
{
  /** The camera aimed at the people (one: around them at any azimuth; several: in front),
    * level within a few degrees: the frames of the earlier datasets. */
  Aimed,
  /** A camera of its own pose (height, pitch, roll drawn from their ranges) and 1 to
    * `people` people anywhere in its view, some cut by the frame's borders; a share of the
    * frames a close-range upper body without a room, and a share with the background
    * removed: what a robot's or a ceiling camera sees. */
  Whole
};

/** "aimed" or "whole". */
const char *synthLayoutName (SynthLayout layout);
/** Inverse of synthLayoutName; false for an unknown name. */
bool parseSynthLayout (const std::string &name, SynthLayout &layout);

/** Options of a synthetic run. */
struct SynthOptions
{
  std::vector<std::string> motion_files;
  double bvh_scale = 0.0;  ///< metres per BVH unit, <= 0: auto per file
  SynthSensor sensor = SynthSensor::Sr4000;
  std::uint64_t seed = 1;
  int subjects = 4;        ///< body shapes drawn from the seed
  /** People per frame, 1-4. One: the camera is placed around the person and aimed at
    * them. Several: they stand at random distances and bearings in front of the camera,
    * partly hiding each other (doc/synthetic.md, "Several people"). */
  int people = 1;
  /** Camera to body (each person's), metres; 0: 1.5-3.5 for one person, 0.8-6 for several. */
  double min_distance = 0.0, max_distance = 0.0;
  /** Camera above the floor, metres; 0: 0.8-1.6 for aimed layouts, 0.6-2.5 for whole scenes. */
  double min_height = 0.0, max_height = 0.0;
  SynthLayout layout = SynthLayout::Aimed;
  // Whole scenes only (layout Whole):
  double min_pitch_deg = -35.0, max_pitch_deg = 10.0;  ///< camera pitch, degrees, up positive
  double max_roll_deg = 10.0;                          ///< camera roll within +-this, degrees
  /** Share of frames showing one person's upper body at 0.7-1.6 m, no room (the
    * background already removed), as a robot's camera at arm's length sees them. */
  double close_range_share = 0.15;
  /** Share of the other frames whose pixels off every person are made invalid, as when a
    * user removed the background before detection. */
  double background_removed_share = 0.2;
  /** How far beyond the image's edges a person's torso may stand, as a share of the image's
    * width and height (people cut by the borders). */
  double border_share = 0.15;
  /** Frame size; 0: the sensor's own. Another size keeps the sensor's field of view (the
    * intrinsics scale with it), so 320x240 is a Kinect frame at half resolution. */
  int width = 0, height = 0;
  /** Kinect v1 (kinect and bonn): the correlation window's side in pixels at 640x480, odd,
    * 1-31 (scaled with the frame size); 0: the model's default (off). On, it takes the
    * fitted foreground weight 1.5 (doc/sensors.md). */
  int kinect_window = 0;
  /** A MakeHuman directory (base.obj, default.mhskel, default_weights.mhw) for mesh
    * bodies (buildMeshBody); empty: capsule and ellipsoid bodies (buildBody). */
  std::string body_mesh;
  /** With body_mesh: each subject gets its own BodyShape (BodyShape::sample, drawn from
    * the seed) and the mesh shaped by MakeHuman's macro targets of body_mesh, so its
    * stature and girth come from the shape (doc/synthetic.md, "Body shapes"). */
  bool body_shapes = false;
  /** With body_mesh: each subject wears clothes and shoes of its own thickness
    * (BodyParams::dress, drawn from the seed), so arms, legs and feet are as wide as a
    * dressed person's; false: the bare mesh. */
  bool clothes = false;
  /** Also paint colour frames (shadeColour; sr4000 and kinect only); the depth is the same
    * as without. */
  bool colour = false;
  /** Desks, chairs, shelves and boxes in the room (walls and the floor always). */
  bool clutter = true;
  /** Pose bank (PoseBank, doc/synthetic.md "Pose bank"): with directories of BVH files
    * or procedural poses, the motion files, the directories' files and the procedural
    * poses become one bank on the pose skeleton, thinned to poses thin_poses metres apart
    * (0: all kept), and frames draw their pose from it. */
  std::vector<std::string> pose_dirs;
  int procedural_poses = 0;     ///< 0-100000
  double thin_poses = 0.0;      ///< metres, 0-1
};

/** Draws and renders frames; frame i depends only on the options and i. */
class SynthGenerator
{
public:
  /** \throws BvhError naming a bad motion file, HumanMeshError naming a bad mesh file,
    * std::invalid_argument for bad options */
  explicit SynthGenerator (const SynthOptions &options);

  const SynthOptions &options () const { return options_; }
  const SensorModel &sensor () const { return sensor_; }
  const std::vector<MotionClip> &clips () const { return clips_; }
  const std::vector<BodyParams> &subjects () const { return subjects_; }

  /** The mesh bodies are made of (unshaped), null for capsule bodies. */
  const HumanMesh *mesh () const { return mesh_.get (); }
  /** The mesh of one subject: its shaped mesh with body_shapes, else mesh().
    * \throws std::out_of_range for a subject out of range */
  const HumanMesh *mesh (int subject) const;
  /** Each subject's body shape; empty without body_shapes. */
  const std::vector<BodyShape> &shapes () const { return shapes_; }
  /** The body a subject has on a clip frame: mesh or capsules, as the options say. */
  BodyModel body (int clip, int clip_frame, int subject) const;

  /** Renders frame `index`. */
  SynthFrame render (std::uint64_t index) const;
  /** \brief Renders frame `index` with the given people (1-255 of them, person k + 1 at
    * people[k]) instead of drawn ones; the camera height, its aim, the room and the
    * noise are drawn from the frame's generator as render() draws them for several people.
    * \throws std::invalid_argument for a clip, frame or subject out of range */
  SynthFrame renderPeople (std::uint64_t index, const std::vector<SynthPersonPlacement> &people) const;
  /** Draws the people of frame `index` as render () does for several (sorted nearest first). */
  std::vector<SynthPersonPlacement> drawPeople (std::uint64_t index) const;
  /** The dataset description: sensor, size, intrinsics, provenance. */
  DatasetInfo datasetInfo () const;

private:
  SynthFrame renderOne (std::uint64_t index) const;
  /** bodies: the people's bodies as body () gives them (null: built here). */
  SynthFrame renderGroup (SynthRng &rng, std::uint64_t index, const std::vector<SynthPersonPlacement> &people,
                          const std::vector<BodyModel> *bodies) const;
  /** Also returns each person's body (as body () gives it), in the placements' order. */
  std::vector<SynthPersonPlacement> drawPeople (std::uint64_t index, std::vector<BodyModel> &bodies) const;
  /** A whole scene (SynthLayout::Whole): the camera's pose drawn first, then the people in
    * its view. */
  SynthFrame renderWhole (std::uint64_t index) const;
  /** Renders people placed on the floor plan, seen by a camera of the given pose (null:
    * aimed at them as render () aims for several people); room: the floor, walls and
    * clutter (false: only the people). */
  SynthFrame renderPlaced (SynthRng &rng, std::uint64_t index, const std::vector<SynthPersonPlacement> &people,
                           const std::vector<BodyModel> *bodies, const Eigen::Isometry3d *world_to_camera,
                           bool room) const;
  /** Horizontal field of view of the stored frames, radians. */
  double horizontalFieldOfView () const;

  SynthOptions options_;
  SensorModel sensor_, render_sensor_;
  std::vector<MotionClip> clips_;
  std::vector<BodyParams> subjects_;
  std::shared_ptr<const HumanMesh> mesh_;
  std::vector<BodyShape> shapes_;                           ///< per subject, with body_shapes
  std::vector<std::shared_ptr<const HumanMesh>> shaped_;  ///< per subject, with body_shapes
  /** The floor under a posed body: its clip's lowest over the whole clip (so hops leave the
    * floor), or, for the pose bank's poses (NaN in floor_), the body's own lowest point, so
    * that the shaped mesh's soles, not the skeleton's joints, stand on it. */
  double floorUnder (int clip, int subject, const BodyModel &body) const;
  std::vector<std::vector<double>> floor_;  ///< [clip][subject]: floor height, clip frame; NaN: each pose's own
};

/** Frame ids: "000123". */
std::string synthFrameId (std::uint64_t index);

/** Timings of writeSyntheticDataset. */
struct SynthRunStats
{
  int frames = 0;
  double render_ms = 0.0, write_ms = 0.0;  ///< totals
  int labels = 0, visible_labels = 0;
};

/** \brief Renders `frames` frames and writes them as an agex dataset (atomically,
  * through DatasetWriter). progress(done, total) is called after each frame.
  * \throws DatasetError if output exists and overwrite is false; BvhError */
SynthRunStats writeSyntheticDataset (const SynthGenerator &generator, int frames, const std::string &output,
                                     bool overwrite, const std::function<void (int, int)> &progress = {});
}  // namespace agex
