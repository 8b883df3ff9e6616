// The depth pipeline's metric settings (doc/pipeline.md, "Metric settings"): frames of one
// scene at 640x480 and 320x240 give the same meshes, a thin limb survives the cleaning at
// both, one- and two-pixel strands and spurs do not; the windows follow the focal length and
// depth; the settings are stored in models and range-checked, and models written before them
// keep their pixel settings.

#include "test_support.h"

#include <agex/detection/depth_pipeline.h>
#include <agex/detection/detector_model.h>
#include <agex/simulation/synthetic_scene.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <map>
#include <sstream>

namespace
{
using namespace agex_test;
using PipelineParams = agex::DepthPipelineParams;
using PipelineResult = agex::DepthPipelineResult;

/** The same camera (a Kinect's field of view) at width x height: f = 525 at 640x480. */
Camera
kinectCamera (int width, int height)
{
  Camera cam;
  cam.width = width;
  cam.height = height;
  cam.fx = cam.fy = 525.0 * width / 640.0;
  cam.cx = (width - 1) / 2.0;
  cam.cy = (height - 1) / 2.0;
  return cam;
}

/** The pipeline settings of the models written before the metric ones. */
PipelineParams
pixelSettings (PipelineParams params = PipelineParams ())
{
  return PipelineParams::pixelSettings (params);
}

/** The cleaning stages on a figure before a wall: no person isolation (a figure is nobody),
  * no floor, the box around the figure's depth. */
PipelineParams
figureSettings (PipelineParams params = PipelineParams ())
{
  params.isolate_people = false;
  params.remove_floor = false;
  params.crop_min = Eigen::Vector3f (-3.f, -3.f, 2.f);
  params.crop_max = Eigen::Vector3f (3.f, 3.f, 3.f);
  return params;
}

/** A body at 2.5 m before a wall at 3.5 m: a 0.2 m disc with limbs 6, 8 and 10 cm wide
  * (half widths 3, 4 and 5 cm) and 0.45-0.55 m long, one of them raised. */
std::vector<Figure>
bodyBeforeAWall ()
{
  Figure body;
  body.centre = Eigen::Vector2d (0.0, 0.1);
  body.depth = 2.5;
  body.disc_radius = 0.2;
  const auto limb = [&body] (double angle_deg, double length, double half_width) {
    const double a = angle_deg * M_PI / 180.0;
    body.limbs.push_back ({Eigen::Vector2d (std::cos (a), std::sin (a)), length, half_width});
  };
  limb (-135.0, 0.55, 0.03);  // raised, up and to the left: the 6 cm "forearm"
  limb (-30.0, 0.45, 0.04);
  limb (80.0, 0.5, 0.05);
  limb (110.0, 0.5, 0.05);
  Figure wall;
  wall.centre = Eigen::Vector2d::Zero ();
  wall.depth = 3.5;
  wall.disc_radius = 100.0;
  return {body, wall};
}

/** A mesh as the camera sees it: its area (each point (z / f)^2) and centroid. */
struct MeshSummary
{
  double area = 0.0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero ();
  int person = -1;
};

/** f: the focal length the areas are measured with (0: the one the pipeline used). */
std::vector<MeshSummary>
summarise (const PipelineResult &result, double f = 0.0)
{
  std::vector<MeshSummary> out;
  if (!(f > 0.0))
    f = result.focal_length;
  for (std::size_t m = 0; m < result.meshes.size (); ++m)
  {
    MeshSummary s;
    for (const auto i : result.meshes[m].indices)
    {
      const auto &p = (*result.filtered)[i];
      s.area += static_cast<double> (p.z) * p.z / (f * f);
      s.centroid += p.getVector3fMap ().cast<double> ();
    }
    s.centroid /= static_cast<double> (result.meshes[m].indices.size ());
    s.person = result.mesh_person.empty () ? -1 : result.mesh_person[m];
    out.push_back (s);
  }
  return out;
}

std::string
describe (const std::vector<MeshSummary> &meshes)
{
  std::ostringstream out;
  for (const auto &m : meshes)
    out << " [" << m.area << " m^2 at " << m.centroid.transpose () << ", person " << m.person << "]";
  return out.str ();
}

/** Each mesh of a has its counterpart in b (the nearest centroid, within 5 cm): the same
  * person, the area within 15%; and as many meshes. (Labelled 640x480 and 320x240, b may be
  * another camera.) */
void
expectSameMeshes (const std::vector<MeshSummary> &a, const std::vector<MeshSummary> &b)
{
  SCOPED_TRACE ("640x480:" + describe (a) + "\n320x240:" + describe (b));
  ASSERT_EQ (a.size (), b.size ());
  for (const auto &m : a)
  {
    const auto other = std::min_element (b.begin (), b.end (), [&m] (const MeshSummary &x, const MeshSummary &y) {
      return (x.centroid - m.centroid).norm () < (y.centroid - m.centroid).norm ();
    });
    EXPECT_LT ((other->centroid - m.centroid).norm (), 0.05);
    EXPECT_NEAR (other->area, m.area, 0.15 * m.area);
    EXPECT_EQ (other->person, m.person);
  }
}

/** Scene index of people in procedural poses (no shared data needed) in a room with clutter,
  * the camera aimed at them from 1.5-3.5 m, rendered by a noise-free Kinect (the
  * quantisation stays) at width x height (f = 525 at 640x480). */
Cloud::Ptr
noiseFreeKinectScene (std::uint64_t index, int width, int height)
{
  static const agex::SynthGenerator generator = [] {
    agex::SynthOptions options;
    options.procedural_poses = 40;
    options.sensor = agex::SynthSensor::Kinect;
    options.seed = 21;
    return agex::SynthGenerator (options);
  }();
  agex::SensorModel exact = agex::renderSensorModel (agex::SynthSensor::Kinect);
  exact.kinect_sigma_q = 0.0;
  exact.kinect_edge_drop = exact.kinect_edge_drop_near = 0.0;
  const agex::SynthFrame frame = generator.render (index);
  agex::SynthRng rng (1);
  agex::SynthFrame view;
  agex::renderScene (frame.scene, agex::scaledTo (exact, width, height), rng, view);
  return Cloud::Ptr (new Cloud (view.cloud));
}

/** Whether a mesh point lies within radius of p. */
bool
meshPointNear (const PipelineResult &result, const Eigen::Vector3f &p, float radius)
{
  for (const int i : result.meshIndices ())
    if (((*result.filtered)[i].getVector3fMap () - p).norm () <= radius)
      return true;
  return false;
}

// ---------------------------------------------------------------------------
// (a) One scene, two resolutions of one camera, the same meshes.

// min_separation reaches AGEX: on the figure (one mesh, three limbs) k = 16 points stop at the
// limbs' tips, the first points of the run without it.
TEST (MetricPipeline, MinSeparationStopsAgexAtTheFiguresExtremities)
{
  PipelineParams params = figureSettings ();
  params.k = 16;
  const Cloud::Ptr cloud = rasterise (bodyBeforeAWall (), kinectCamera (640, 480));
  const PipelineResult all = agex::runDepthPipeline (cloud, params);
  params.min_separation = 0.2f;  // shorter than every limb, longer than the bumps along them
  const PipelineResult some = agex::runDepthPipeline (cloud, params);
  ASSERT_EQ (all.meshes.size (), 1u);
  ASSERT_EQ (all.interest_points.size (), 16u);
  ASSERT_GE (some.interest_points.size (), 4u);  // the centre and the three tips
  ASSERT_LT (some.interest_points.size (), all.interest_points.size ());
  for (std::size_t i = 0; i < some.interest_points.size (); ++i)
  {
    EXPECT_EQ (some.interest_points[i].getVector3fMap (), all.interest_points[i].getVector3fMap ()) << i;
    if (i > 0)
    {
      EXPECT_GE (some.interest_points[i].geodesic_distance, 0.2f) << i;
    }
  }
  EXPECT_LT (all.interest_points[some.interest_points.size ()].geodesic_distance, 0.2f);
}

TEST (MetricPipeline, AFigureGivesTheSameMeshesAt640x480And320x240AndOnA512x424Camera)
{
  const auto figures = bodyBeforeAWall ();
  const PipelineResult full = agex::runDepthPipeline (rasterise (figures, kinectCamera (640, 480)), figureSettings ());
  const PipelineResult half = agex::runDepthPipeline (rasterise (figures, kinectCamera (320, 240)), figureSettings ());
  EXPECT_NEAR (full.focal_length, 525.f, 0.5f);
  EXPECT_NEAR (half.focal_length, 262.5f, 0.5f);
  const auto a = summarise (full), b = summarise (half);
  ASSERT_FALSE (a.empty ());
  expectSameMeshes (a, b);
  // A Kinect v2's 512x424 (f = 366, a wider view) sees the same figure: the same meshes.
  Camera v2;
  v2.width = 512;
  v2.height = 424;
  v2.fx = v2.fy = 366.0;
  v2.cx = 255.5;
  v2.cy = 211.5;
  const PipelineResult wide = agex::runDepthPipeline (rasterise (figures, v2), figureSettings ());
  EXPECT_NEAR (wide.focal_length, 366.f, 0.5f);
  expectSameMeshes (a, summarise (wide));
  // The limbs survive, joined to the disc: one mesh.
  EXPECT_EQ (a.size (), 1u) << describe (a);

  // The pixel settings give other meshes at the two resolutions: the median, the mixed-pixel
  // window and the erosion do not scale alike (here the 8 and 10 cm limbs, narrower than
  // twice the erosion, go at one resolution and not at the other, or come apart).
  const auto pa = summarise (agex::runDepthPipeline (rasterise (figures, kinectCamera (640, 480)),
                                                     figureSettings (pixelSettings ())),
                             525.0),
             pb = summarise (agex::runDepthPipeline (rasterise (figures, kinectCamera (320, 240)),
                                                     figureSettings (pixelSettings ())),
                             262.5);
  std::cout << "pixel settings, 640x480:" << describe (pa) << "\n                320x240:" << describe (pb) << "\n";
}

TEST (MetricPipeline, SynthesisedPeopleGiveTheSamePersonsAndLargestMeshesAtBothResolutions)
{
  // Each scene of noiseFreeKinectScene at 640x480 and at 320x240 (half the focal length); the
  // default pipeline, person isolation included. What must agree: the persons, each person's cleaned area, and its largest
  // mesh. (The small meshes do not always agree: a piece cut off by a depth step or by the
  // erosion of the part it grows from comes apart at one resolution and not at the other,
  // or lies just above the minimum area at one of them.)
  int persons = 0;
  for (std::uint64_t index = 0; index < 6; ++index)
  {
    SCOPED_TRACE ("frame " + std::to_string (index));
    PipelineResult results[2];
    for (int k = 0; k < 2; ++k)
      results[k] = agex::runDepthPipeline (noiseFreeKinectScene (index, 640 / (k + 1), 480 / (k + 1)), PipelineParams ());
    const auto a = summarise (results[0]), b = summarise (results[1]);
    SCOPED_TRACE ("640x480:" + describe (a) + "\n320x240:" + describe (b));
    ASSERT_EQ (results[0].persons.size (), results[1].persons.size ());
    for (int person = 0; person < static_cast<int> (results[0].persons.size ()); ++person)
    {
      double area[2] = {0.0, 0.0}, largest[2] = {0.0, 0.0};
      for (int k = 0; k < 2; ++k)
        for (const auto &m : k == 0 ? a : b)
          if (m.person == person)
          {
            area[k] += m.area;
            largest[k] = std::max (largest[k], m.area);
          }
      EXPECT_GT (area[0], 0.05) << "person " << person;
      EXPECT_NEAR (area[1], area[0], 0.15 * area[0]) << "person " << person << "'s meshes";
      EXPECT_NEAR (largest[1], largest[0], 0.15 * largest[0]) << "person " << person << "'s largest mesh";
      ++persons;
    }
  }
  EXPECT_GE (persons, 5);
}

TEST (MetricPipeline, AWorkingDensityGivesTheSamePersonsAndMeshesFromEveryFewPixels)
{
  // Synthesised people at 1.5-3.5 m by a noise-free 640x480 Kinect, the pipeline at the
  // sensor's density and at a working spacing of 1 cm (every second to fourth pixel, by the
  // farthest person's depth): the same persons, each person's area within 15%; the interest
  // points and meshes name pixels of the working frame, which map back to the input's.
  PipelineParams working;
  working.working_spacing = 0.01f;
  int persons = 0, sampled = 0;
  for (std::uint64_t index = 0; index < 6; ++index)
  {
    SCOPED_TRACE ("frame " + std::to_string (index));
    const Cloud::Ptr cloud = noiseFreeKinectScene (index, 640, 480);
    const PipelineResult full = agex::runDepthPipeline (cloud, PipelineParams ());
    const PipelineResult work = agex::runDepthPipeline (cloud, working);
    EXPECT_EQ (full.stride, 1);
    float farthest = 0.f;
    for (const auto &info : full.person_info)
      farthest = std::max (farthest, info.distance);
    // The stride the farthest person's depth asks for (1 beyond 3.5 m at f = 525).
    const int expected = farthest > 0.f ? std::clamp (static_cast<int> (std::lround (0.01 * 525.0 / farthest)), 1, 8) : 1;
    EXPECT_EQ (work.stride, expected < 2 ? 1 : expected) << "farthest person at " << farthest << " m";
    EXPECT_NEAR (work.focal_length * work.stride, 525.f, 0.5f);
    EXPECT_EQ (work.input_width, 640u);
    EXPECT_EQ (work.input_height, 480u);
    ASSERT_TRUE (work.filtered);
    EXPECT_EQ (work.filtered->width, (640u - 1u - static_cast<unsigned> (work.offset)) / work.stride + 1u);
    EXPECT_EQ (static_cast<bool> (work.frame), work.stride > 1);
    sampled += work.stride > 1;
    const auto a = summarise (full), b = summarise (work);
    SCOPED_TRACE ("every pixel:" + describe (a) + "\nworking:" + describe (b));
    ASSERT_EQ (full.persons.size (), work.persons.size ());
    for (int person = 0; person < static_cast<int> (full.persons.size ()); ++person)
    {
      double area[2] = {0.0, 0.0};
      for (int k = 0; k < 2; ++k)
        for (const auto &m : k == 0 ? a : b)
          if (m.person == person)
            area[k] += m.area;
      EXPECT_GT (area[0], 0.05) << "person " << person;
      EXPECT_NEAR (area[1], area[0], 0.15 * area[0]) << "person " << person;
      ++persons;
    }
    // Each interest point's input pixel is where the camera sees its position.
    for (const auto &p : work.interest_points)
    {
      const Eigen::Vector2i pixel = work.inputPixel (p.v * static_cast<int> (work.filtered->width) + p.u);
      const auto &original = (*cloud)[static_cast<std::size_t> (pixel.y ()) * 640 + pixel.x ()];
      EXPECT_NEAR (525.0 * p.x / p.z + 319.5, pixel.x (), 1.0);
      EXPECT_NEAR (525.0 * p.y / p.z + 239.5, pixel.y (), 1.0);
      EXPECT_TRUE (std::isfinite (original.z));
    }
    // The meshes at the input's size cover about stride^2 input pixels per working pixel.
    const auto in_input = work.meshesInInput ();
    ASSERT_EQ (in_input.size (), work.meshes.size ());
    for (std::size_t m = 0; m < work.meshes.size (); ++m)
    {
      EXPECT_LE (in_input[m].indices.size (), work.meshes[m].indices.size () * work.stride * work.stride);
      EXPECT_GE (in_input[m].indices.size (), work.meshes[m].indices.size ());
      EXPECT_TRUE (std::is_sorted (in_input[m].indices.begin (), in_input[m].indices.end ()));
    }
  }
  EXPECT_GE (persons, 5);
  EXPECT_GE (sampled, 3);  // most of these people are near enough to be sampled
}

// ---------------------------------------------------------------------------
// (b) A 6 cm limb at 2.5 m survives the cleaning at both resolutions.

TEST (MetricPipeline, ASixCentimetreLimbSurvivesAtBothResolutions)
{
  const auto figures = bodyBeforeAWall ();
  const Figure &body = figures[0];
  const Figure::Limb &forearm = body.limbs[0];
  for (const int width : {640, 320})
  {
    SCOPED_TRACE (std::to_string (width) + "x" + std::to_string (width * 3 / 4));
    const Cloud::Ptr cloud = rasterise (figures, kinectCamera (width, width * 3 / 4));
    const PipelineResult result = agex::runDepthPipeline (cloud, figureSettings ());
    // Its tip, and its axis every 5 cm from where it leaves the disc to the tip: a mesh point
    // within 5 cm, and all on the disc's mesh.
    EXPECT_TRUE (meshPointNear (result, body.tip3D (0), 0.05f)) << "the tip";
    for (double s = body.disc_radius; s <= forearm.length; s += 0.05)
    {
      const Eigen::Vector2d on_axis = body.centre + s * forearm.direction;
      const Eigen::Vector3f p (static_cast<float> (on_axis.x ()), static_cast<float> (on_axis.y ()),
                               static_cast<float> (body.depth));
      EXPECT_TRUE (meshPointNear (result, p, 0.05f)) << "the axis " << s << " m from the disc's centre";
    }
    EXPECT_EQ (result.meshes.size (), 1u);
    // The pixel settings (the erosion 3.5 cm deep, 4 passes at 320x240) take it whole at
    // 320x240: its tip has no mesh point within 10 cm. (At 640x480 a thread of it stays: 7
    // passes, and on a diagonal a pass takes only 0.7 pixels.)
    const PipelineResult pixels = agex::runDepthPipeline (cloud, figureSettings (pixelSettings ()));
    EXPECT_TRUE (meshPointNear (pixels, body.centre3D (), 0.05f)) << "pixel settings: the disc";
    if (width == 320)
    {
      EXPECT_FALSE (meshPointNear (pixels, body.tip3D (0), 0.10f)) << "pixel settings";
    }
  }
}

// ---------------------------------------------------------------------------
// (c) One- and two-pixel strands and one-pixel spurs still go, at both resolutions.

TEST (MetricPipeline, OneAndTwoPixelStrandsAndSpursGoAtBothResolutions)
{
  const auto figures = bodyBeforeAWall ();
  const Figure &body = figures[0];
  for (const int width : {640, 320})
  {
    const Camera cam = kinectCamera (width, width * 3 / 4);
    SCOPED_TRACE (std::to_string (cam.width) + "x" + std::to_string (cam.height));
    const Cloud::Ptr cloud = rasterise (figures, cam);
    // From the disc's top, up 10 cm: a one-pixel and a two-pixel strand at the disc's depth;
    // along the disc's bottom, one-pixel spurs every 6 pixels.
    const auto column = [&] (double x) { return static_cast<int> (std::lround (x * cam.fx / body.depth + cam.cx)); };
    const auto row = [&] (double y) { return static_cast<int> (std::lround (y * cam.fy / body.depth + cam.cy)); };
    const auto inDisc = [&] (int u, int v) {
      return (Eigen::Vector2d ((u - cam.cx) * body.depth / cam.fx, (v - cam.cy) * body.depth / cam.fy) - body.centre)
                 .norm () <= body.disc_radius;
    };
    std::vector<int> added;
    const auto add = [&] (int u, int v) {
      if (isFinite ((*cloud) (u, v)) && (*cloud) (u, v).z < 3.f)
        return;  // on the body already (a limb): not a strand
      (*cloud) (u, v) = rayPoint (cam, u, v, body.depth);
      added.push_back (v * cam.width + u);
    };
    const int strand_length = static_cast<int> (std::lround (0.1 * cam.fy / body.depth));
    for (const auto &[x, strand_width] : std::vector<std::pair<double, int>>{{-0.05, 1}, {0.05, 2}})
    {
      const int u0 = column (body.centre.x () + x);
      int top = row (body.centre.y () - body.disc_radius - 0.02);
      while (!(inDisc (u0, top) && inDisc (u0 + strand_width - 1, top)))
        ++top;  // the disc's first row under both columns
      for (int v = top - strand_length; v < top; ++v)
        for (int u = u0; u < u0 + strand_width; ++u)
          if (!inDisc (u, v))
            add (u, v);
    }
    const int bottom_row = row (body.centre.y () + body.disc_radius);
    for (int u = column (body.centre.x () - 0.1); u <= column (body.centre.x () + 0.1); u += 6)
    {
      int v = bottom_row - 3;
      while (inDisc (u, v))
        ++v;
      add (u, v);  // the first pixel below the disc in that column
    }
    ASSERT_GT (added.size (), 20u);
    const PipelineResult result = agex::runDepthPipeline (cloud, figureSettings ());
    const std::vector<int> surface = result.meshIndices ();
    int kept = 0;
    for (const int i : added)
      kept += std::find (surface.begin (), surface.end (), i) != surface.end ();
    EXPECT_EQ (kept, 0) << "strand and spur pixels on a mesh, of " << added.size ();
    // Control: without the spur filter they are the disc's.
    PipelineParams no_spurs = figureSettings ();
    no_spurs.spur_iterations = 0;
    const std::vector<int> raw = agex::runDepthPipeline (cloud, no_spurs).meshIndices ();
    int on_disc = 0;
    for (const int i : added)
      on_disc += std::find (raw.begin (), raw.end (), i) != raw.end ();
    EXPECT_GT (on_disc, static_cast<int> (added.size ()) * 3 / 4);
  }
}

// ---------------------------------------------------------------------------
// The windows follow the focal length and the depth; the focal length given is used.

TEST (MetricPipeline, WindowsFollowTheFocalLengthAndDepth)
{
  const auto figures = bodyBeforeAWall ();
  const PipelineResult full = agex::runDepthPipeline (rasterise (figures, kinectCamera (640, 480)), figureSettings ());
  const PipelineResult half = agex::runDepthPipeline (rasterise (figures, kinectCamera (320, 240)), figureSettings ());
  // 0.025 m at 2.5 m: 5.25 px at f = 525 (3x3 samples 2 apart: 5 px), 2.6 px at 262.5 (3x3).
  EXPECT_EQ (full.median_window, 5);
  EXPECT_EQ (half.median_window, 3);
  // 0.004 rad: 2.1 px at f = 525, 1.05 at 262.5.
  EXPECT_EQ (full.mixed_window_radius, 2);
  EXPECT_EQ (half.mixed_window_radius, 1);
  // The pixel settings are pixels at both.
  const PipelineResult pixels = agex::runDepthPipeline (rasterise (figures, kinectCamera (320, 240)),
                                                        figureSettings (pixelSettings ()));
  EXPECT_EQ (pixels.median_window, 3);
  EXPECT_EQ (pixels.mixed_window_radius, 2);
  EXPECT_EQ (pixels.focal_length, 0.f) << "no setting needs one";

  // A focal length given is used as it is, and one out of range is refused.
  agex::DepthPipeline<pcl::PointXYZ> pipeline (figureSettings ());
  pipeline.setInputCloud (rasterise (figures, kinectCamera (320, 240)));
  pipeline.setFocalLength (300.f, 300.f);
  PipelineResult given;
  pipeline.compute (given);
  EXPECT_EQ (given.focal_length, 300.f);
  EXPECT_THROW (pipeline.setFocalLength (-1.f, 300.f), std::invalid_argument);
  EXPECT_THROW (pipeline.setFocalLength (300.f, 0.f), std::invalid_argument);
  EXPECT_THROW (pipeline.setFocalLength (std::nanf (""), 300.f), std::invalid_argument);
  EXPECT_NO_THROW (pipeline.setFocalLength (0.f, 0.f));
  pipeline.compute (given);
  EXPECT_NEAR (given.focal_length, 262.5f, 0.5f) << "0, 0: estimated again";
}

// ---------------------------------------------------------------------------
// Model files: the metric settings are stored and range-checked; older models keep pixels.

TEST (MetricSettings, StoredInModelsAndOlderModelsKeepTheirPixelSettings)
{
  const PipelineParams defaults;
  EXPECT_EQ (defaults.median_window, -1);
  EXPECT_EQ (defaults.mixed_window_radius, -1);
  EXPECT_GT (defaults.spur_min_width, 0.f);
  EXPECT_GT (defaults.min_mesh_area, 0.f);
  nlohmann::json doc = defaults.toJson ();
  for (const char *key : {"median_extent", "mixed_window_angle", "spur_min_width", "min_mesh_area"})
    EXPECT_TRUE (doc.contains (key)) << key;
  PipelineParams changed;
  changed.median_extent = 0.03f;
  changed.mixed_window_angle = 0.006f;
  changed.spur_min_width = 0.04f;
  changed.min_mesh_area = 0.01f;
  changed.working_spacing = 0.012f;
  changed.min_separation = 0.06f;
  const PipelineParams read = PipelineParams::fromJson (changed.toJson (), "m.yml");
  EXPECT_EQ (read.working_spacing, 0.012f);
  EXPECT_EQ (read.min_separation, 0.06f);
  EXPECT_EQ (read.median_extent, 0.03f);
  EXPECT_EQ (read.mixed_window_angle, 0.006f);
  EXPECT_EQ (read.spur_min_width, 0.04f);
  EXPECT_EQ (read.min_mesh_area, 0.01f);

  // A model written before them: its pixel settings, no width rule, no area.
  nlohmann::json old = pixelSettings ().toJson ();
  for (const char *key :
       {"median_extent", "mixed_window_angle", "spur_min_width", "min_mesh_area", "working_spacing", "min_separation"})
    old.erase (key);
  const PipelineParams before = PipelineParams::fromJson (old, "old.yml");
  EXPECT_EQ (before.working_spacing, 0.f);  // the sensor's density, as trained
  EXPECT_EQ (before.min_separation, 0.f);   // k AGEX points on every mesh, as trained
  EXPECT_EQ (before.median_window, 3);
  EXPECT_EQ (before.mixed_window_radius, 2);
  EXPECT_EQ (before.spur_min_width, 0.f);
  EXPECT_EQ (before.min_mesh_size, -1);
  EXPECT_EQ (before.min_mesh_area, 0.f);

  // Out of range: refused, the key named.
  for (const auto &[key, value] : std::vector<std::pair<std::string, double>>{{"median_extent", -0.01},
                                                                              {"median_extent", 5},
                                                                              {"median_window", -2},
                                                                              {"mixed_window_angle", 0},
                                                                              {"mixed_window_angle", 1},
                                                                              {"mixed_window_radius", 0},
                                                                              {"spur_min_width", -0.01},
                                                                              {"spur_min_width", 2},
                                                                              {"min_mesh_area", -1},
                                                                              {"min_mesh_area", 1e6},
                                                                              {"working_spacing", -0.001},
                                                                              {"working_spacing", 0.06},
                                                                              {"min_separation", -0.01},
                                                                              {"min_separation", 1.5}})
  {
    nlohmann::json bad = defaults.toJson ();
    bad[key] = value;
    try
    {
      PipelineParams::fromJson (bad, "m.yml");
      ADD_FAILURE () << key << " = " << value << " was accepted";
    }
    catch (const std::invalid_argument &e)
    {
      EXPECT_NE (std::string (e.what ()).find ("m.yml: pipeline." + key), std::string::npos) << e.what ();
    }
  }

  // The sliding-window stride: metres in new models, pixels in older ones.
  agex::DetectorSettings settings;
  settings.kind = agex::DetectorKind::SlidingWindow;
  EXPECT_EQ (settings.sliding_window.stride, -1);
  nlohmann::json sw = settings.toJson ();
  EXPECT_EQ (agex::DetectorSettings::fromJson (sw, "sw.yml").sliding_window.stride_metres,
             settings.sliding_window.stride_metres);
  sw["sliding_window"].erase ("stride_metres");
  sw["sliding_window"]["stride"] = 3;
  EXPECT_EQ (agex::DetectorSettings::fromJson (sw, "sw.yml").sliding_window.stride, 3);
  sw["sliding_window"]["stride_metres"] = 0;
  EXPECT_THROW (agex::DetectorSettings::fromJson (sw, "sw.yml"), std::invalid_argument);
}

TEST (MetricSettings, BundledModelsRunMetricSettings)
{
  // The bundled models are trained on several resolutions and distances
  // (scripts/train_bundled_models.sh): every window, width and size is metric or follows the
  // focal length, and the floor may tilt as a camera looking down tilts it.
  for (const char *name : {"agex_bonn.yml", "agex_bonn_sw.yml", "agex_bonn_agex.yml"})
  {
    SCOPED_TRACE (name);
    const std::string path = std::string (AGEX_SOURCE_DIR) + "/data/models/" + name;
    const agex::DetectorModel model = agex::DetectorModel::load (path);
    const PipelineParams &p = model.settings ().pipeline;
    EXPECT_EQ (p.median_window, -1);
    EXPECT_EQ (p.mixed_window_radius, -1);
    EXPECT_GT (p.spur_min_width, 0.f);
    EXPECT_GT (p.min_mesh_area, 0.f);
    EXPECT_EQ (p.min_mesh_size, 0);
    EXPECT_GE (p.floor_max_tilt_deg, 45.f);
    if (model.settings ().kind == agex::DetectorKind::SlidingWindow)
    {
      EXPECT_EQ (model.settings ().sliding_window.stride, -1);
      EXPECT_GT (model.settings ().sliding_window.stride_metres, 0.f);
    }
  }
}
}  // namespace
