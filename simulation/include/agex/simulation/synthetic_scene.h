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

#include <agex/simulation/body_shape.h>
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
// ---------------------------------------------------------------------------

// ---------------------------------------------------------------------------
// Bodies

/** Per-subject body shape; every length of the body model is in metres. */
struct BodyParams
{
  double height_scale = 1.0;  ///< multiplies the skeleton (and every size below)
  double girth = 1.0;         ///< multiplies torso and limb radii
  double head_scale = 1.0;    ///< multiplies the head ellipsoid
  double arm_girth = 1.0;     ///< extra factor on arm radii
  double leg_girth = 1.0;     ///< extra factor on leg radii
  double torso_depth = 1.0;   ///< front-back size of the torso
  double reflectivity = 0.7;  ///< clothes and skin, 0..1

  /** Draws a subject: height 0.92-1.08, girth 0.85-1.25, head 0.93-1.07, arms and legs
    * 0.9-1.12, torso depth 0.9-1.2, reflectivity 0.45-0.9. */
  static BodyParams random (SynthRng &rng);
  /** "height_scale=1.02 girth=0.93 ..." */
  std::string describe () const;
};

/** The joints the body model hangs on, found by name in a BVH skeleton. Two naming
  * schemes are known: CMU ASF conversions (LeftUpLeg, LeftLeg, LeftFoot, LeftToeBase,
  * Spine, Spine1, Neck, Head, LeftArm, LeftForeArm, LeftHand, LeftHandIndex1) and the
  * bvh11 / CMU 131 scheme (LeftHip, LeftKnee, LeftAnkle, LeftToe, Chest, Chest2,
  * lowerneck, Head, LeftShoulder, LeftElbow, LeftWrist, LFingers); index 0 = left. */
struct SkeletonMap
{
  int root = -1, spine_base = -1, spine_mid = -1, neck = -1, head = -1, head_end = -1;
  int shoulder[2] = {-1, -1}, elbow[2] = {-1, -1}, wrist[2] = {-1, -1}, hand_end[2] = {-1, -1};
  int hip[2] = {-1, -1}, knee[2] = {-1, -1}, ankle[2] = {-1, -1}, toe[2] = {-1, -1}, toe_end[2] = {-1, -1};
  /** Rest-pose directions in the file's world frame: the subject's left, up and forward. */
  Eigen::Matrix3d rest_basis = Eigen::Matrix3d::Identity ();

  /** \brief Finds the joints. \throws BvhError naming the file and the missing joint */
  static SkeletonMap find (const BvhMotion &motion);
};

/** A motion capture clip ready to pose bodies. */
struct MotionClip
{
  BvhMotion motion;
  SkeletonMap map;
  double scale = 1.0;          ///< metres per file unit
  bool scale_auto = true;      ///< scale was detected (autoBvhScale)
  std::string sequence;        ///< the file's stem

  /** \brief Reads a BVH file; scale <= 0 means auto (autoBvhScale).
    * \throws BvhError naming the file (and line) */
  static MotionClip load (const std::string &path, double scale = 0.0);
};

/** A posed body in the clip's world frame (metres, Y up). */
struct BodyModel
{
  std::vector<SynthPrimitive> primitives;  ///< all SynthObject::Person
  /** Tip and base of the head (0), the hands (1: left, 2: right) and feet (3: left,
    * 4: right); tips on the body surface. */
  Eigen::Vector3d tip[5], base[5];
  /** Per tip: the primitives of its part (head ellipsoid; hand; foot and toes) and the
    * depth tolerance of its visibility test: the part's radius + 3 cm, since the
    * surface seen near a tip on the part's silhouette is up to a radius in front of it. */
  std::vector<int> tip_primitives[5];
  double tip_tolerance[5] = {0, 0, 0, 0, 0};
  /** Middle of the torso (between the root and the neck). */
  Eigen::Vector3d centre = Eigen::Vector3d::Zero ();
  /** Lowest and highest point of the body (Y). */
  double lowest = 0.0, highest = 0.0;
  /** The same body after a rigid transform. */
  BodyModel transformed (const Eigen::Isometry3d &transform) const;
};

/** \brief Poses the body model on frame `frame` of a clip (-1 = rest pose). */
BodyModel buildBody (const MotionClip &clip, int frame, const BodyParams &params);

class HumanMesh;

/** \brief Poses the MakeHuman mesh body on frame `frame` of a clip (-1 = rest pose):
  * the mesh is scaled to the clip's rest height times params.height_scale, shaped by
  * the other params (a shaped mesh, HumanMesh::isShaped, keeps its own size and girth
  * instead: only params.reflectivity is used, and the clip's motion is scaled to the
  * mesh's height; doc/synthetic.md, "Body shapes"), and each bone follows the motion capture segment it lies on
  * (rotation of the segment's joint, then turned so the bone points where the segment
  * does; doc/synthetic.md). One mesh primitive per HumanMesh::Part, in its order
  * (trunk, head, hands, feet, arms, legs); tips are mesh vertices (top of the head, middle finger tips,
  * toe fronts), bases the neck, wrist and ankle joints. */
BodyModel buildMeshBody (const MotionClip &clip, int frame, const BodyParams &params, const HumanMesh &mesh);

/** Heads of the mesh's bones (indexed like mesh.bones()) posed as buildMeshBody poses
  * them: the posed skeleton. */
std::vector<Eigen::Vector3d> meshBoneHeads (const MotionClip &clip, int frame, const BodyParams &params,
                                            const HumanMesh &mesh);

/** Lowest point (Y) of the posed mesh body's feet and a sample of its other vertices:
  * what the floor is placed by, without building the whole body. */
double meshBodyLowest (const MotionClip &clip, int frame, const BodyParams &params, const HumanMesh &mesh);

/** Height of the body model in the clip's rest pose (head top to sole), metres. */
double restStandingHeight (const MotionClip &clip, const BodyParams &params = BodyParams ());

// ---------------------------------------------------------------------------
// Rendering

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

/** \brief Labels for the body's tips and bases (camera frame, the body's primitives
  * first in frame.scene), projected with the sensor's intrinsics. A tip is visible if
  * its pixel is in the image and within labelWindow() pixels of it a pixel with a valid
  * depth within the part's tolerance of the tip's depth sees the tip's own part (the
  * noise-free centre ray hits one of its primitives). Instance 0 is the one on the
  * image's left (smaller tip u). Fills frame.labels and frame.label_checks. */
void makeLabels (const BodyModel &body_in_camera, const SensorModel &sensor, SynthFrame &frame);

/** \brief The same for one person of several: appends the five labels of a body whose
  * primitives start at index first_primitive of frame.scene, with PartLabel::person =
  * person (and the checks' primitives as scene indices). */
void appendPersonLabels (const BodyModel &body_in_camera, const SensorModel &sensor, int first_primitive, int person,
                         SynthFrame &frame);

/** Half size of the label visibility window: 1 (3x3) for sr4000, 2 (5x5) for kinect. */
int labelWindow (const SensorModel &sensor);

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
  /** A MakeHuman directory (base.obj, default.mhskel, default_weights.mhw) for mesh
    * bodies (buildMeshBody); empty: capsule and ellipsoid bodies (buildBody). */
  std::string body_mesh;
  /** With body_mesh: each subject gets its own BodyShape (BodyShape::sample, drawn from
    * the seed) and the mesh shaped by MakeHuman's macro targets of body_mesh, so its
    * stature and girth come from the shape (doc/synthetic.md, "Body shapes"). */
  bool body_shapes = false;
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
  std::vector<std::vector<double>> floor_;  ///< [clip][subject]: floor height, clip frame
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
