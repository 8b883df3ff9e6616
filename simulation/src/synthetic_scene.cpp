#include <agex/simulation/synthetic_scene.h>
#include <agex/simulation/pose_bank.h>

#include <agex/simulation/bonn_sensor.h>
#include <agex/simulation/camera_pose.h>
#include <agex/simulation/human_mesh.h>
#include <agex/simulation/make_human_targets.h>
#include <agex/simulation/renderer.h>
#include <agex/simulation/room.h>

#include <pcl/common/io.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <numeric>
#include <set>
#include <sstream>
#include <stdexcept>

namespace agex
{
namespace
{
constexpr double kInf = std::numeric_limits<double>::infinity ();



}  // namespace

// ---------------------------------------------------------------------------
// The generator

namespace
{
/** Distances left at 0: 1.5-3.5 m for one person (aimed at), 0.8-6 m for several or a
  * whole scene; camera heights left at 0: 0.8-1.6 m aimed, 0.6-2.5 m in whole scenes. */
SynthOptions
withDefaultDistances (SynthOptions options)
{
  const bool whole = options.layout == SynthLayout::Whole;
  const bool several = options.people > 1 || whole;
  if (options.min_distance == 0.0)
    options.min_distance = several ? 0.8 : 1.5;
  if (options.max_distance == 0.0)
    options.max_distance = several ? 6.0 : 3.5;
  if (options.min_height == 0.0)
    options.min_height = whole ? 0.6 : 0.8;
  if (options.max_height == 0.0)
    options.max_height = whole ? 2.5 : 1.6;
  return options;
}

/** A sensor's model at another frame size with the same field of view; the size must keep
  * the aspect ratio of the sensor's pixels. */
SensorModel
atFrameSize (SensorModel model, int width, int height)
{
  if (width == 0 && height == 0)
    return model;
  if (width < 16 || height < 16 || width > 4096 || height > 4096)
    throw std::invalid_argument ("the frame size must be 16-4096 pixels a side, got " + std::to_string (width) + "x" +
                                 std::to_string (height));
  if (std::abs (static_cast<double> (width) * model.height - static_cast<double> (height) * model.width) >
      0.02 * model.width * model.height)
    throw std::invalid_argument ("the frame size " + std::to_string (width) + "x" + std::to_string (height) +
                                 " does not keep the sensor's aspect ratio (" + std::to_string (model.width) + "x" +
                                 std::to_string (model.height) + ")");
  return scaledTo (model, width, height);
}

bool
isShare (double value)
{
  return value >= 0.0 && value <= 1.0;
}

/** Why whole-scene options cannot be used, empty if they can. */
std::string
wholeSceneProblem (const SynthOptions &o)
{
  if (!(o.min_pitch_deg >= -89.0 && o.max_pitch_deg <= 89.0 && o.min_pitch_deg <= o.max_pitch_deg))
    return "camera pitch must satisfy -89 <= min <= max <= 89 degrees";
  if (!(o.max_roll_deg >= 0.0 && o.max_roll_deg <= 90.0))
    return "camera roll must be 0-90 degrees";
  if (!isShare (o.close_range_share))
    return "the close-range share must be 0-1";
  if (!isShare (o.background_removed_share))
    return "the background-removed share must be 0-1";
  if (!(o.border_share >= 0.0 && o.border_share <= 0.5))
    return "the border share must be 0-0.5";
  return {};
}
}  // namespace

const char *
synthLayoutName (SynthLayout layout)
{
  return layout == SynthLayout::Whole ? "whole" : "aimed";
}

bool
parseSynthLayout (const std::string &name, SynthLayout &layout)
{
  if (name == "aimed")
    layout = SynthLayout::Aimed;
  else if (name == "whole")
    layout = SynthLayout::Whole;
  else
    return false;
  return true;
}

SynthGenerator::SynthGenerator (const SynthOptions &options_in)
  : options_ (withDefaultDistances (options_in)), sensor_ (sensorModel (options_in.sensor)),
    render_sensor_ (renderSensorModel (options_in.sensor))
{
  const SynthOptions &options = options_;
  if (options.kinect_window != 0)
  {
    if (options.kinect_window < 1 || options.kinect_window > 31 || options.kinect_window % 2 == 0)
      throw std::invalid_argument ("the kinect correlation window must be an odd 1-31 pixels, got " +
                                   std::to_string (options.kinect_window));
    for (SensorModel *model : {&sensor_, &render_sensor_})
    {
      model->kinect_window = options.kinect_window;
      model->kinect_foreground_weight = options.kinect_window > 1 ? 1.5 : 1.0;
    }
  }
  if (options.width != 0 || options.height != 0)
  {
    if (options.sensor == SynthSensor::Bonn)
      throw std::invalid_argument ("the bonn sensor's frames are its 144x176 portrait view; no other frame size");
    sensor_ = atFrameSize (sensor_, options.width, options.height);
    render_sensor_ = atFrameSize (render_sensor_, options.width, options.height);
  }
  if (!(options.min_height > 0.0 && options.max_height <= 10.0))
    throw std::invalid_argument ("camera heights must lie in (0, 10] metres");
  if (!(options.max_distance <= 20.0))
    throw std::invalid_argument ("camera distances must be at most 20 metres");
  if (options.layout == SynthLayout::Whole)
  {
    const std::string problem = wholeSceneProblem (options);
    if (!problem.empty ())
      throw std::invalid_argument (problem);
  }
  const bool pose_bank = !options.pose_dirs.empty () || options.procedural_poses > 0;
  if (options.motion_files.empty () && !pose_bank)
    throw std::invalid_argument ("no motion files given");
  if (options.procedural_poses < 0 || options.procedural_poses > 100000)
    throw std::invalid_argument ("procedural poses must be 0-100000, got " + std::to_string (options.procedural_poses));
  if (!(options.thin_poses >= 0.0 && options.thin_poses <= 1.0))
    throw std::invalid_argument ("the pose thinning distance must be 0-1 m, got " + std::to_string (options.thin_poses));
  if (options.subjects < 1)
    throw std::invalid_argument ("the number of subjects must be at least 1");
  if (options.people < 1 || options.people > 4)
    throw std::invalid_argument ("the number of people per frame must be 1-4, got " + std::to_string (options.people));
  if (!(options.min_distance > 0.3) || options.max_distance < options.min_distance)
    throw std::invalid_argument ("camera distances must satisfy 0.3 < min <= max");
  if (options.max_height < options.min_height)
    throw std::invalid_argument ("camera heights must satisfy min <= max");
  if (options.colour && options.sensor == SynthSensor::Bonn)
    throw std::invalid_argument ("colour frames need sensor sr4000 or kinect (bonn frames are a grey depth view)");
  if (pose_bank)
    clips_.push_back (poseBankOf (options).clip ());
  else
    for (const auto &path : options.motion_files)
      clips_.push_back (MotionClip::load (path, options.bvh_scale));
  SynthRng rng = SynthRng::forItem (options.seed, ~0ull);
  for (int s = 0; s < options.subjects; ++s)
    subjects_.push_back (BodyParams::random (rng));
  if (options.body_shapes && options.body_mesh.empty ())
    throw std::invalid_argument ("body shapes need a MakeHuman body mesh (body_mesh)");
  if (options.clothes && options.body_mesh.empty ())
    throw std::invalid_argument ("clothes need a MakeHuman body mesh (body_mesh)");
  if (options.clothes)
  {
    // Their own generator too: every other draw stays as without clothes.
    SynthRng clothes_rng = SynthRng::forItem (options.seed, ~2ull);
    for (auto &subject : subjects_)
      subject.dress (clothes_rng);
  }
  if (!options.body_mesh.empty ())
    mesh_ = std::make_shared<const HumanMesh> (HumanMesh::load (options.body_mesh));
  if (options.body_shapes)
  {
    // Shapes from their own generator, so the subjects' BodyParams stay as without.
    SynthRng shape_rng = SynthRng::forItem (options.seed, ~1ull);
    const MakeHumanTargets targets = MakeHumanTargets::load (options.body_mesh, mesh_->baseVertexCount ());
    for (int s = 0; s < options.subjects; ++s)
    {
      shapes_.push_back (BodyShape::sample (shape_rng));
      shaped_.push_back (std::make_shared<const HumanMesh> (mesh_->shaped (targets, shapes_.back ())));
    }
  }
  // The floor of a clip for a subject: the lowest the body gets over the whole clip; a
  // bank pose stands on its own lowest point (floorUnder).
  floor_.resize (clips_.size ());
  for (std::size_t c = 0; c < clips_.size (); ++c)
    for (std::size_t s = 0; s < subjects_.size (); ++s)
    {
      if (pose_bank)
      {
        floor_[c].push_back (std::numeric_limits<double>::quiet_NaN ());
        continue;
      }
      const BodyParams &params = subjects_[s];
      const HumanMesh *mesh = this->mesh (static_cast<int> (s));
      double lowest = kInf;
      for (int f = 0; f < clips_[c].motion.frameCount (); ++f)
        lowest = std::min (lowest, mesh ? meshBodyLowest (clips_[c], f, params, *mesh)
                                        : buildBody (clips_[c], f, params).lowest);
      floor_[c].push_back (lowest);
    }
}

double
SynthGenerator::floorUnder (int clip, int subject, const BodyModel &body) const
{
  const double floor_y = floor_[static_cast<std::size_t> (clip)][static_cast<std::size_t> (subject)];
  return std::isnan (floor_y) ? body.lowest : floor_y;
}

const HumanMesh *
SynthGenerator::mesh (int subject) const
{
  if (subject < 0 || subject >= static_cast<int> (subjects_.size ()))
    throw std::out_of_range ("subject " + std::to_string (subject) + " of " + std::to_string (subjects_.size ()));
  return shaped_.empty () ? mesh_.get () : shaped_[static_cast<std::size_t> (subject)].get ();
}

BodyModel
SynthGenerator::body (int clip, int clip_frame, int subject) const
{
  const MotionClip &c = clips_.at (static_cast<std::size_t> (clip));
  const BodyParams &params = subjects_.at (static_cast<std::size_t> (subject));
  const HumanMesh *mesh = this->mesh (subject);
  return mesh ? buildMeshBody (c, clip_frame, params, *mesh) : buildBody (c, clip_frame, params);
}

namespace
{
/** Orders people (and their bodies alike) by distance, nearest first; ties keep their order. */
void
sortNearestFirst (std::vector<SynthPersonPlacement> &people, std::vector<BodyModel> &bodies)
{
  std::vector<std::size_t> order (people.size ());
  std::iota (order.begin (), order.end (), 0);
  std::stable_sort (order.begin (), order.end (),
                    [&] (std::size_t a, std::size_t b) { return people[a].distance < people[b].distance; });
  std::vector<SynthPersonPlacement> sorted;
  std::vector<BodyModel> sorted_bodies;
  for (const std::size_t i : order)
  {
    sorted.push_back (people[i]);
    sorted_bodies.push_back (std::move (bodies[i]));
  }
  people = std::move (sorted);
  bodies = std::move (sorted_bodies);
}

/** How far a body reaches horizontally from its centre (the middle of its torso). */
double
horizontalReach (const BodyModel &body)
{
  auto off = [&] (const Eigen::Vector3d &p) { return std::hypot (p.x () - body.centre.x (), p.z () - body.centre.z ()); };
  double reach = 0.0;
  for (const auto &p : body.primitives)
  {
    if (p.shape == SynthPrimitive::Shape::Capsule)
      reach = std::max (reach, std::max (off (p.a), off (p.b)) + p.radius);
    else if (p.shape == SynthPrimitive::Shape::Mesh)
      for (const auto &v : p.mesh->vertices ())
        reach = std::max (reach, off (p.centre + p.axes * v));
    else
    {
      Eigen::Vector3d c;
      double r;
      if (p.boundingSphere (c, r))
        reach = std::max (reach, off (c) + r);
    }
  }
  return reach;
}

/** Where a placement stands on the floor plan: the camera at the origin looking along +z,
  * its right along -x. */
Eigen::Vector3d
placementSpot (const SynthPersonPlacement &p)
{
  return Eigen::Vector3d (-p.distance * std::sin (p.bearing), 0.0, p.distance * std::cos (p.bearing));
}

/** Where to put a person whose random spots were all taken: the free spot of a grid over
  * the ranges (25 cm by 1/14 of the bearings) nearest to the last spot drawn (p, which
  * it replaces); false if every grid spot is taken. */
bool
nearestFreeGridSpot (double min_distance, double max_distance, double max_bearing,
                     const std::function<bool (const SynthPersonPlacement &)> &free, SynthPersonPlacement &p)
{
  const SynthPersonPlacement last = p;
  double best = kInf;
  bool found = false;
  for (double d = min_distance; d <= max_distance + 1e-9; d += 0.25)
    for (int b = 0; b <= 14; ++b)
    {
      SynthPersonPlacement q = last;
      q.distance = d;
      q.bearing = max_bearing * (b / 7.0 - 1.0);
      const double gap = (placementSpot (q) - placementSpot (last)).norm ();
      if (gap < best && free (q))
      {
        best = gap;
        p = q;
        found = true;
      }
    }
  return found;
}

/** The stems of the people's motion files, sorted, without repeats, joined by '+'. */
std::string
groupSequence (const std::vector<MotionClip> &clips, const std::vector<SynthPersonPlacement> &people)
{
  std::set<std::string> stems;
  for (const auto &p : people)
    stems.insert (clips[static_cast<std::size_t> (p.clip)].sequence);
  std::string sequence;
  for (const auto &stem : stems)
    sequence += (sequence.empty () ? "" : "+") + stem;
  return sequence;
}

}  // namespace

SynthFrame
SynthGenerator::render (std::uint64_t index) const
{
  if (options_.layout == SynthLayout::Whole)
    return renderWhole (index);
  if (options_.people == 1)
    return renderOne (index);
  std::vector<BodyModel> bodies;
  const std::vector<SynthPersonPlacement> people = drawPeople (index, bodies);
  SynthRng rng = SynthRng::forItem (options_.seed, index);
  return renderGroup (rng, index, people, &bodies);
}

SynthFrame
SynthGenerator::renderPeople (std::uint64_t index, const std::vector<SynthPersonPlacement> &people) const
{
  if (people.empty () || people.size () > 255)
    throw std::invalid_argument ("renderPeople: 1-255 people");
  for (const auto &p : people)
    if (p.clip < 0 || p.clip >= static_cast<int> (clips_.size ()) || p.subject < 0 ||
        p.subject >= static_cast<int> (subjects_.size ()) || p.clip_frame < 0 ||
        p.clip_frame >= clips_[static_cast<std::size_t> (p.clip)].motion.frameCount () || !std::isfinite (p.distance) ||
        !std::isfinite (p.bearing) || !std::isfinite (p.facing))
      throw std::invalid_argument ("renderPeople: a placement's clip, clip frame or subject is out of range, or a "
                                   "distance or angle is not finite");
  SynthRng rng = SynthRng::forItem (options_.seed, index);
  return renderGroup (rng, index, people, nullptr);
}

std::vector<SynthPersonPlacement>
SynthGenerator::drawPeople (std::uint64_t index) const
{
  std::vector<BodyModel> bodies;
  return drawPeople (index, bodies);
}

double
SynthGenerator::horizontalFieldOfView () const
{
  return 2.0 * std::atan (0.5 * sensor_.width / sensor_.intrinsics.fx);
}

std::vector<SynthPersonPlacement>
SynthGenerator::drawPeople (std::uint64_t index, std::vector<BodyModel> &bodies) const
{
  // A stream of its own, so that renderPeople (i, drawPeople (i)) is render (i).
  SynthRng rng = SynthRng::forItem (options_.seed ^ 0x9E0913E5A11CE5EDull, index);
  const double half_fov = 0.5 * horizontalFieldOfView ();
  std::vector<SynthPersonPlacement> people;
  std::vector<double> reach;
  bodies.clear ();
  auto clear = [&] (const SynthPersonPlacement &p, double r) {
    for (std::size_t j = 0; j < people.size (); ++j)
      if ((placementSpot (p) - placementSpot (people[j])).norm () < r + reach[j] + 0.1)
        return false;
    return true;
  };
  for (int k = 0; k < options_.people; ++k)
  {
    SynthPersonPlacement p;
    p.clip = rng.index (static_cast<int> (clips_.size ()));
    p.clip_frame = rng.index (clips_[static_cast<std::size_t> (p.clip)].motion.frameCount ());
    p.subject = rng.index (static_cast<int> (subjects_.size ()));
    p.facing = rng.uniform (0.0, 2.0 * M_PI);
    BodyModel body = this->body (p.clip, p.clip_frame, p.subject);
    const double r = horizontalReach (body);
    // 40% of the people after the first stand in line with an earlier one (within 0.5 m
    // of its line of sight), so that one hides part of the other.
    const bool in_line = k > 0 && rng.chance (0.4);
    const int other = k > 0 ? rng.index (k) : 0;
    bool placed = false;
    for (int attempt = 0; attempt < 50 && !placed; ++attempt)
    {
      p.distance = rng.uniform (options_.min_distance, options_.max_distance);
      if (in_line)
      {
        const double lateral = rng.uniform (-0.5, 0.5);
        p.bearing = people[static_cast<std::size_t> (other)].bearing + lateral / p.distance;
      }
      else
        p.bearing = rng.uniform (-0.85 * half_fov, 0.85 * half_fov);
      placed = clear (p, r);
    }
    if (!placed)  // crowded
      placed = nearestFreeGridSpot (options_.min_distance, options_.max_distance, 0.85 * half_fov,
                                    [&] (const SynthPersonPlacement &q) { return clear (q, r); }, p);
    while (!placed)  // very rare: no room within the ranges; step back along the bearing
    {
      p.distance += 0.25;
      placed = clear (p, r);
    }
    people.push_back (p);
    reach.push_back (r);
    bodies.push_back (std::move (body));
  }
  sortNearestFirst (people, bodies);  // person 1 is the nearest
  return people;
}

SynthFrame
SynthGenerator::renderGroup (SynthRng &rng, std::uint64_t index, const std::vector<SynthPersonPlacement> &people,
                             const std::vector<BodyModel> *bodies) const
{
  return renderPlaced (rng, index, people, bodies, nullptr, true);
}

SynthFrame
SynthGenerator::renderPlaced (SynthRng &rng, std::uint64_t index, const std::vector<SynthPersonPlacement> &people,
                              const std::vector<BodyModel> *bodies, const Eigen::Isometry3d *world_to_camera,
                              bool with_room) const
{
  SynthFrame frame;
  frame.people = people;
  frame.clip = people.front ().clip;
  frame.clip_frame = people.front ().clip_frame;
  frame.subject = people.front ().subject;
  frame.sequence = groupSequence (clips_, people);
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY ();

  // The people on the floor plan (floor at y = 0): each body turned by its facing about
  // the vertical through its torso, which stands at its spot.
  std::vector<BodyModel> placed;
  std::vector<SynthPrimitive> people_primitives;
  std::vector<int> first_primitive;
  double mid_height = 0.0, mean_distance = 0.0, farthest = 0.0;
  for (std::size_t k = 0; k < people.size (); ++k)
  {
    const SynthPersonPlacement &p = people[k];
    const BodyModel body = bodies ? (*bodies)[k] : this->body (p.clip, p.clip_frame, p.subject);
    const double floor_y = floorUnder (p.clip, p.subject, body);
    const Eigen::Isometry3d to_plan = Eigen::Translation3d (placementSpot (p)) * Eigen::AngleAxisd (p.facing, up) *
                                      Eigen::Translation3d (-body.centre.x (), -floor_y, -body.centre.z ());
    placed.push_back (body.transformed (to_plan));
    first_primitive.push_back (static_cast<int> (people_primitives.size ()));
    for (SynthPrimitive prim : placed.back ().primitives)
    {
      prim.person = static_cast<std::uint8_t> (k + 1);
      people_primitives.push_back (std::move (prim));
    }
    mid_height += 0.5 * (body.lowest + body.highest) - floor_y;
    mean_distance += p.distance;
    farthest = std::max (farthest, placementSpot (p).z ());
  }
  mid_height /= static_cast<double> (people.size ());
  mean_distance /= static_cast<double> (people.size ());

  // The camera at the floor plan's origin, aimed along +z at the people's mean distance
  // and middle height, with a jitter (pan sigma ~3 degrees, 10 cm up or down), roll and pitch.
  Eigen::Vector3d camera, aim;
  if (world_to_camera)
  {
    frame.world_to_camera = *world_to_camera;
    camera = world_to_camera->inverse ().translation ();
    aim = camera + world_to_camera->linear ().row (2).transpose ();
  }
  else
  {
    const double height = rng.uniform (options_.min_height, options_.max_height);
    camera = Eigen::Vector3d (0.0, height, 0.0);
    aim = Eigen::Vector3d (0.0, mid_height, mean_distance);
    aim.x () += rng.normal (0.0, 0.05 * mean_distance);
    aim.y () += rng.normal (0.0, 0.1);
    const double roll = rng.normal (0.0, 3.0) * M_PI / 180.0, pitch = rng.normal (0.0, 2.0) * M_PI / 180.0;
    frame.world_to_camera = worldToCamera (camera, aim, roll, pitch);
  }

  // The room: walls behind the farthest person, clutter from 0.8 m in front of the
  // camera to the back wall, across the field of view.
  SynthScene world;
  world.primitives = people_primitives;
  RoomFrame room;
  room.ahead = aim - camera;
  room.ahead.y () = 0.0;
  if (room.ahead.norm () < 1e-6)  // looking straight down
    room.ahead = Eigen::Vector3d::UnitZ ();
  room.ahead.normalize ();
  room.lateral = up.cross (room.ahead);
  room.camera = camera;
  room.floor_y = 0.0;
  room.anchor = room.ahead * farthest;
  room.people = &people_primitives;
  room.along_min = -(farthest - 0.8);
  room.across = std::max (1.8, (farthest + 1.0) * std::tan (0.5 * horizontalFieldOfView ()) + 0.5);
  if (with_room)
  {
    const double wall_behind = addFloorAndWalls (rng, room, world);
    if (options_.clutter)
      addGroupClutter (rng, room, wall_behind, world);
  }

  const SynthScene scene = world.transformed (frame.world_to_camera);
  renderScene (scene, render_sensor_, rng, frame);
  if (options_.colour)
  {
    SynthRng colour_rng = SynthRng::forItem (options_.seed ^ 0xC0105EEDC0105EEDull, index);
    shadeColour (render_sensor_, colour_rng, frame);
  }
  if (options_.sensor == SynthSensor::Bonn)
    toBonnView (render_sensor_, sensor_, frame);
  frame.labels.clear ();
  frame.label_checks.clear ();
  for (std::size_t k = 0; k < placed.size (); ++k)
    appendPersonLabels (placed[k].transformed (frame.world_to_camera), sensor_, first_primitive[k],
                        static_cast<int> (k + 1), frame);
  return frame;
}

namespace
{
/** Makes every pixel off the people invalid, as a user's background removal does. */
void
removeBackground (SynthFrame &frame)
{
  const float nan = std::numeric_limits<float>::quiet_NaN ();
  for (std::size_t i = 0; i < frame.cloud.size () && i < frame.object.size (); ++i)
    if (frame.object[i] != SynthObject::Person)
      frame.cloud[i].x = frame.cloud[i].y = frame.cloud[i].z = nan;
}
}  // namespace

SynthFrame
SynthGenerator::renderWhole (std::uint64_t index) const
{
  SynthRng rng = SynthRng::forItem (options_.seed, index);
  const double degree = M_PI / 180.0;
  const CameraIntrinsics &k = sensor_.intrinsics;
  auto draw_pose = [&] (SynthPersonPlacement &p) {
    p.clip = rng.index (static_cast<int> (clips_.size ()));
    p.clip_frame = rng.index (clips_[static_cast<std::size_t> (p.clip)].motion.frameCount ());
    p.subject = rng.index (static_cast<int> (subjects_.size ()));
    p.facing = rng.uniform (0.0, 2.0 * M_PI);
  };
  auto floor_of = [&] (const SynthPersonPlacement &p, const BodyModel &body) { return floorUnder (p.clip, p.subject, body); };
  std::vector<SynthPersonPlacement> people;
  std::vector<BodyModel> bodies;

  if (rng.chance (options_.close_range_share))
  {
    // One upper body at arm's length: the camera at chest height looking at the torso,
    // nothing else in the scene.
    SynthPersonPlacement p;
    draw_pose (p);
    p.distance = rng.uniform (0.7, 1.6);
    p.bearing = rng.normal (0.0, 0.05);
    BodyModel body = this->body (p.clip, p.clip_frame, p.subject);
    const double floor_y = floor_of (p, body);
    const double top = body.highest - floor_y, torso = body.centre.y () - floor_y;
    const Eigen::Vector3d spot = Eigen::Vector3d (-p.distance * std::sin (p.bearing), 0.0, p.distance * std::cos (p.bearing));
    const Eigen::Vector3d camera (0.0, std::max (0.3, top - 0.35 + rng.normal (0.0, 0.1)), 0.0);
    Eigen::Vector3d aim = spot + Eigen::Vector3d (rng.normal (0.0, 0.05), torso + 0.15 + rng.normal (0.0, 0.1), 0.0);
    const Eigen::Isometry3d world_to_camera =
        worldToCamera (camera, aim, rng.uniform (-options_.max_roll_deg, options_.max_roll_deg) * degree, 0.0);
    people.push_back (p);
    bodies.push_back (std::move (body));
    return renderPlaced (rng, index, people, &bodies, &world_to_camera, false);
  }

  // The camera's pose first, then people wherever it sees them.
  const double height = rng.uniform (options_.min_height, options_.max_height);
  const double pitch = rng.uniform (options_.min_pitch_deg, options_.max_pitch_deg) * degree;
  const double roll = rng.uniform (-options_.max_roll_deg, options_.max_roll_deg) * degree;
  const Eigen::Vector3d camera (0.0, height, 0.0);
  // worldToCamera's pitch turns the view down; ours is up positive.
  const Eigen::Isometry3d world_to_camera = worldToCamera (camera, camera + Eigen::Vector3d::UnitZ (), roll, -pitch);
  const double half_fov = 0.5 * horizontalFieldOfView ();
  const double border = options_.border_share;
  const int count = 1 + rng.index (options_.people);
  std::vector<double> reach;
  for (int n = 0; n < count; ++n)
  {
    SynthPersonPlacement p;
    draw_pose (p);
    BodyModel body = this->body (p.clip, p.clip_frame, p.subject);
    const double r = horizontalReach (body), torso = body.centre.y () - floor_of (p, body);
    // Where the torso must be seen: within the image grown by the border share.
    auto seen = [&] (const SynthPersonPlacement &q) {
      const Eigen::Vector3d c = world_to_camera * (placementSpot (q) + Eigen::Vector3d (0.0, torso, 0.0));
      if (c.z () < 0.3)
        return false;
      const double u = k.fx * c.x () / c.z () + k.cx, v = k.fy * c.y () / c.z () + k.cy;
      return u >= -border * sensor_.width && u <= (1.0 + border) * sensor_.width && v >= -border * sensor_.height &&
             v <= (1.0 + border) * sensor_.height;
    };
    auto clear = [&] (const SynthPersonPlacement &q) {
      for (std::size_t j = 0; j < people.size (); ++j)
        if ((placementSpot (q) - placementSpot (people[j])).norm () < r + reach[j] + 0.1)
          return false;
      return true;
    };
    bool placed = false;
    for (int attempt = 0; attempt < 100 && !placed; ++attempt)
    {
      p.distance = rng.uniform (options_.min_distance, options_.max_distance);
      p.bearing = rng.uniform (-1.0, 1.0) * std::min (1.5, half_fov * (1.0 + 2.0 * border));
      placed = seen (p) && clear (p);
    }
    if (!placed && !people.empty ())
      continue;  // no room for another person in this view
    people.push_back (p);  // the first person stays even if the view never showed them
    reach.push_back (r);
    bodies.push_back (std::move (body));
  }
  sortNearestFirst (people, bodies);  // person 1 is the nearest, as in render ()
  const bool background_removed = rng.chance (options_.background_removed_share);
  SynthFrame frame = renderPlaced (rng, index, people, &bodies, &world_to_camera, true);
  if (background_removed)
    removeBackground (frame);
  return frame;
}

SynthFrame
SynthGenerator::renderOne (std::uint64_t index) const
{
  SynthRng rng = SynthRng::forItem (options_.seed, index);
  SynthFrame frame;
  frame.clip = rng.index (static_cast<int> (clips_.size ()));
  const MotionClip &clip = clips_[frame.clip];
  frame.clip_frame = rng.index (clip.motion.frameCount ());
  frame.subject = rng.index (static_cast<int> (subjects_.size ()));
  frame.sequence = clip.sequence;
  const BodyModel body = this->body (frame.clip, frame.clip_frame, frame.subject);
  const double floor_y = floorUnder (frame.clip, frame.subject, body);

  // Camera: around the person at a random azimuth, distance and height, aimed at the
  // torso with a jitter (sometimes a large one, so the person leaves the frame).
  const double distance = rng.uniform (options_.min_distance, options_.max_distance);
  const double azimuth = rng.uniform (0.0, 2.0 * M_PI);
  const double height = rng.uniform (options_.min_height, options_.max_height);
  const Eigen::Vector3d camera (body.centre.x () + distance * std::cos (azimuth), floor_y + height,
                                body.centre.z () + distance * std::sin (azimuth));
  const double jitter = rng.chance (0.12) ? 0.35 : 0.1;
  Eigen::Vector3d aim (body.centre.x (), 0.5 * (body.lowest + body.highest), body.centre.z ());
  aim.x () += rng.normal (0.0, jitter);
  aim.y () += rng.normal (0.0, jitter);
  aim.z () += rng.normal (0.0, jitter);
  const double roll = rng.normal (0.0, 3.0) * M_PI / 180.0, pitch = rng.normal (0.0, 2.0) * M_PI / 180.0;
  frame.world_to_camera = worldToCamera (camera, aim, roll, pitch);

  // The room: floor, back wall behind the person, maybe a side wall, clutter.
  SynthScene world;
  world.primitives = body.primitives;
  RoomFrame room;
  room.anchor = body.centre;
  room.ahead = aim - camera;
  room.ahead.y () = 0.0;
  room.ahead.normalize ();
  room.lateral = Eigen::Vector3d::UnitY ().cross (room.ahead);  // to the camera's left
  room.camera = camera;
  room.floor_y = floor_y;
  room.people = &body.primitives;
  if (options_.clutter)
    addRoom (rng, room, world);
  else
    addFloorAndWalls (rng, room, world);

  const SynthScene scene = world.transformed (frame.world_to_camera);
  renderScene (scene, render_sensor_, rng, frame);
  if (options_.colour)
  {
    // A stream of its own, so colour frames have the same depth as depth-only ones.
    SynthRng colour_rng = SynthRng::forItem (options_.seed ^ 0xC0105EEDC0105EEDull, index);
    shadeColour (render_sensor_, colour_rng, frame);
  }
  if (options_.sensor == SynthSensor::Bonn)
    toBonnView (render_sensor_, sensor_, frame);
  makeLabels (body.transformed (frame.world_to_camera), sensor_, frame);
  return frame;
}

DatasetInfo
SynthGenerator::datasetInfo () const
{
  DatasetInfo info;
  info.name = std::string ("synthetic-") + synthSensorName (options_.sensor) + "-seed" + std::to_string (options_.seed);
  info.sensor = synthSensorName (options_.sensor);
  info.width = sensor_.width;
  info.height = sensor_.height;
  info.intrinsics = sensor_.intrinsics;
  info.depth_scale = 1.0;
  info.units = "m";
  info.part_labels = synthPartNames ();
  info.person_labels = true;
  std::ostringstream p;
  p << "agex_synth: synthetic " << info.sensor << " frames (" << sensor_.width << "x" << sensor_.height
    << ") of " << (mesh_ ? "MakeHuman mesh bodies (" + options_.body_mesh + ")" : std::string ("capsule/ellipsoid bodies"))
    << " posed by motion capture; motion:";
  for (const auto &clip : clips_)
    p << " " << clip.motion.path () << " (" << clip.motion.frameCount () << " frames, " << clip.scale << " m/unit"
      << (clip.scale_auto ? " auto" : "") << ")";
  p << "; seed " << options_.seed << "; camera " << options_.min_distance << "-" << options_.max_distance
    << " m from the body, " << options_.min_height << "-" << options_.max_height << " m high";
  if (options_.people > 1)
    p << "; " << options_.people << " people per frame (doc/synthetic.md, \"Several people\")";
  p << "; subjects:";
  for (std::size_t s = 0; s < subjects_.size (); ++s)
    p << " #" << s << " " << subjects_[s].describe ()
      << (s < shapes_.size () ? " shape " + shapes_[s].describe () + " (" + std::to_string (std::lround (shaped_[s]->height () * 1000.0)) + " mm)" : "")
      << (s + 1 < subjects_.size () ? ";" : "");
  p << "; each frame draws (clip, clip frame, subject, camera, room, noise) from its own generator; see "
       "doc/synthetic.md";
  info.provenance = p.str ();
  return info;
}

std::string
synthFrameId (std::uint64_t index)
{
  std::ostringstream out;
  out << std::setw (6) << std::setfill ('0') << index;
  return out.str ();
}

SynthRunStats
writeSyntheticDataset (const SynthGenerator &generator, int frames, const std::string &output, bool overwrite,
                       const std::function<void (int, int)> &progress)
{
  if (frames < 1)
    throw std::invalid_argument ("the number of frames must be at least 1");
  DatasetWriter writer (output, generator.datasetInfo (), overwrite);
  SynthRunStats stats;
  using clock = std::chrono::steady_clock;
  for (int i = 0; i < frames; ++i)
  {
    const auto t0 = clock::now ();
    const SynthFrame frame = generator.render (static_cast<std::uint64_t> (i));
    const auto t1 = clock::now ();
    const std::string id = synthFrameId (static_cast<std::uint64_t> (i));
    if (frame.colour.empty ())
      writer.addFrame (id, frame.sequence, frame.cloud, frame.labels);
    else
    {
      pcl::PointCloud<pcl::PointXYZRGBA> coloured;
      pcl::copyPointCloud (frame.cloud, coloured);
      for (std::size_t p = 0; p < coloured.size (); ++p)
      {
        coloured[p].r = frame.colour[p][0];
        coloured[p].g = frame.colour[p][1];
        coloured[p].b = frame.colour[p][2];
        coloured[p].a = 255;
      }
      writer.addFrame (id, frame.sequence, coloured, frame.labels);
    }
    const int w = generator.sensor ().width, h = generator.sensor ().height;
    // cv::Mat views of the frame's own buffers (not written to).
    writer.addPartLabels (id, cv::Mat (h, w, CV_8UC1, const_cast<std::uint8_t *> (frame.part_label.data ())));
    writer.addPersonLabels (id, cv::Mat (h, w, CV_8UC1, const_cast<std::uint8_t *> (frame.person_label.data ())));
    const auto t2 = clock::now ();
    stats.render_ms += std::chrono::duration<double, std::milli> (t1 - t0).count ();
    stats.write_ms += std::chrono::duration<double, std::milli> (t2 - t1).count ();
    ++stats.frames;
    for (const auto &l : frame.labels)
    {
      ++stats.labels;
      stats.visible_labels += l.visible ? 1 : 0;
    }
    if (progress)
      progress (i + 1, frames);
  }
  writer.commit ();
  return stats;
}
}  // namespace agex
