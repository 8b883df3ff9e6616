#include <agex/simulation/renderer.h>

#include <agex/simulation/depth_sensor.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace agex
{
namespace
{
constexpr double kInf = std::numeric_limits<double>::infinity ();
const float kNaN = std::numeric_limits<float>::quiet_NaN ();
}  // namespace

// ---------------------------------------------------------------------------
// RayCaster

RayCaster::RayCaster (const SynthScene &scene, const SensorModel &sensor, double widen_right_px_m,
                      double widen_left_px_m)
  : scene_ (scene), w_ (sensor.width), h_ (sensor.height)
{
  tiles_x_ = (w_ + kTile - 1) / kTile;
  tiles_y_ = (h_ + kTile - 1) / kTile;
  bins_.resize (static_cast<std::size_t> (tiles_x_) * tiles_y_);
  const CameraIntrinsics &k = sensor.intrinsics;
  for (std::size_t i = 0; i < scene.primitives.size (); ++i)
  {
    const SynthPrimitive &p = scene.primitives[i];
    Eigen::Vector3d c;
    double r;
    if (!p.boundingSphere (c, r))
    {
      planes_.push_back (static_cast<int> (i));
      continue;
    }
    if (c.z () + r < 0.01)
      continue;  // behind the camera
    Box box;
    box.index = static_cast<int> (i);
    box.c = c;
    box.r2 = r * r;
    if (c.z () - r < 0.05)
    {
      box.u0 = 0;
      box.v0 = 0;
      box.u1 = w_ - 1;
      box.v1 = h_ - 1;
    }
    else
    {
      double u0 = kInf, u1 = -kInf, v0 = kInf, v1 = -kInf;
      for (const double z : {c.z () - r, c.z () + r})
        for (const double x : {c.x () - r, c.x () + r})
          for (const double y : {c.y () - r, c.y () + r})
          {
            const double u = k.fx * x / z + k.cx, v = k.fy * y / z + k.cy;
            u0 = std::min (u0, u);
            u1 = std::max (u1, u);
            v0 = std::min (v0, v);
            v1 = std::max (v1, v);
          }
      // Shadow rays from a projector beside the camera: widen along x by the disparity.
      const double zn = std::max (c.z () - r, 0.05);
      u0 -= widen_left_px_m / zn;
      u1 += widen_right_px_m / zn;
      if (u1 < -1 || v1 < -1 || u0 > w_ || v0 > h_)
        continue;
      box.u0 = std::max (0, static_cast<int> (std::floor (u0)) - 1);
      box.v0 = std::max (0, static_cast<int> (std::floor (v0)) - 1);
      box.u1 = std::min (w_ - 1, static_cast<int> (std::ceil (u1)) + 1);
      box.v1 = std::min (h_ - 1, static_cast<int> (std::ceil (v1)) + 1);
    }
    const int b = static_cast<int> (boxes_.size ());
    boxes_.push_back (box);
    for (int ty = box.v0 / kTile; ty <= box.v1 / kTile; ++ty)
      for (int tx = box.u0 / kTile; tx <= box.u1 / kTile; ++tx)
        bins_[static_cast<std::size_t> (ty) * tiles_x_ + tx].push_back (b);
  }
}

RayHit
RayCaster::trace (int u, int v, const Eigen::Vector3d &o, const Eigen::Vector3d &d, bool planes) const
{
  RayHit best;
  Eigen::Vector3d n, best_n = Eigen::Vector3d::Zero ();
  int triangle = -1;
  if (planes)
    for (const int i : planes_)
    {
      const double t = scene_.primitives[i].intersect (o, d, 1e-6, &n);
      if (t > 0 && (best.t < 0 || t < best.t))
      {
        best.t = t;
        best.primitive = i;
        best.triangle = -1;
        best_n = n;
      }
    }
  for (const int b : bins_[static_cast<std::size_t> (v / kTile) * tiles_x_ + u / kTile])
  {
    const Box &box = boxes_[b];
    if (u < box.u0 || u > box.u1 || v < box.v0 || v > box.v1)
      continue;
    // Bounding sphere test first.
    const Eigen::Vector3d oc = box.c - o;
    const double along = oc.dot (d);
    if (oc.squaredNorm () - along * along > box.r2)
      continue;
    if (best.t > 0 && along - std::sqrt (box.r2) > best.t)
      continue;
    const double t = scene_.primitives[box.index].intersect (o, d, 1e-6, &n, &triangle);
    if (t > 0 && (best.t < 0 || t < best.t))
    {
      best.t = t;
      best.primitive = box.index;
      best.triangle = triangle;
      best_n = n;
    }
  }
  if (best.t > 0)
    best.cos = std::abs (best_n.dot (d));
  return best;
}

bool
RayCaster::anyAt (int u, int v) const
{
  for (const int b : bins_[static_cast<std::size_t> (v / kTile) * tiles_x_ + u / kTile])
  {
    const Box &box = boxes_[b];
    if (u >= box.u0 && u <= box.u1 && v >= box.v0 && v <= box.v1)
      return true;
  }
  return false;
}

bool
RayCaster::occluded (int u, int v, const Eigen::Vector3d &o, const Eigen::Vector3d &d, double length) const
{
  for (const int b : bins_[static_cast<std::size_t> (v / kTile) * tiles_x_ + u / kTile])
  {
    const Box &box = boxes_[b];
    if (u < box.u0 || u > box.u1 || v < box.v0 || v > box.v1)
      continue;
    const Eigen::Vector3d oc = box.c - o;
    const double along = oc.dot (d);
    if (oc.squaredNorm () - along * along > box.r2)
      continue;
    const double t = scene_.primitives[box.index].intersect (o, d, 1e-6, nullptr);
    if (t > 0 && t < length)
      return true;
  }
  return false;
}

// ---------------------------------------------------------------------------
// Helpers shared with the sensor models

pcl::PointXYZ
pointOnPixelRay (const CameraIntrinsics &k, int u, int v, double z)
{
  return pcl::PointXYZ (static_cast<float> ((u - k.cx) * z / k.fx), static_cast<float> ((v - k.cy) * z / k.fy),
                        static_cast<float> (z));
}

void
clearLabelsWithoutDepth (SynthFrame &frame)
{
  for (std::size_t i = 0; i < frame.part_label.size (); ++i)
    if (!std::isfinite (frame.cloud.points[i].z))
      frame.part_label[i] = frame.person_label[i] = 0;
}

// ---------------------------------------------------------------------------
// The ideal render

namespace
{
/** Sizes the frame's cloud and ground truth to the sensor, everything invalid. */
void
resetFrame (const SynthScene &scene, const SensorModel &sensor, SynthFrame &frame)
{
  const int w = sensor.width, h = sensor.height;
  const std::size_t n = static_cast<std::size_t> (w) * h;
  frame.scene = scene;
  frame.cloud = pcl::PointCloud<pcl::PointXYZ> (static_cast<std::uint32_t> (w), static_cast<std::uint32_t> (h),
                                                pcl::PointXYZ (kNaN, kNaN, kNaN));
  frame.cloud.is_dense = false;
  frame.object.assign (n, SynthObject::None);
  frame.primitive.assign (n, -1);
  frame.ideal_z.assign (n, kNaN);
  frame.sample_min_z.assign (n, kNaN);
  frame.sample_max_z.assign (n, kNaN);
  frame.clean_z.assign (n, kNaN);
  frame.part_label.assign (n, 0);
  frame.person_label.assign (n, 0);
}

/** Pass 1: the nearest hit of the ray through every pixel centre (row-major). */
std::vector<RayHit>
traceCentreRays (const RayCaster &caster, const SensorModel &sensor, const PixelRays &ray)
{
  const int w = sensor.width, h = sensor.height;
  const Eigen::Vector3d origin = Eigen::Vector3d::Zero ();
  std::vector<RayHit> centre (static_cast<std::size_t> (w) * h);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
      centre[static_cast<std::size_t> (v) * w + u] = caster.trace (u, v, origin, ray (u, v), true);
  return centre;
}

/** True if the centre rays of pixel (u, v) and of its 8 neighbours (clamped at the
  * border) all see the same primitive. */
bool
neighboursSeeTheSamePrimitive (const std::vector<RayHit> &centre, int u, int v, int w, int h)
{
  const std::size_t i = static_cast<std::size_t> (v) * w + u;
  for (int dv = -1; dv <= 1; ++dv)
    for (int du = -1; du <= 1; ++du)
    {
      const int uu = std::clamp (u + du, 0, w - 1), vv = std::clamp (v + dv, 0, h - 1);
      if (centre[static_cast<std::size_t> (vv) * w + uu].primitive != centre[i].primitive)
        return false;
    }
  return true;
}

/** Pass 2 for one pixel: ss x ss samples where the centre rays of the pixel and its 8
  * neighbours do not all see the same primitive; elsewhere the centre sample stands for
  * all of them (a smooth surface averages to its centre value). */
void
samplePixel (const RayCaster &caster, const std::vector<RayHit> &centre, const PixelRays &ray, int u, int v, int w,
             int h, int ss, PixelSamples &samples)
{
  const std::size_t i = static_cast<std::size_t> (v) * w + u;
  const Eigen::Vector3d origin = Eigen::Vector3d::Zero ();
  samples.uniform = ss <= 1 || neighboursSeeTheSamePrimitive (centre, u, v, w, h);
  samples.count = 1;
  if (samples.uniform)
  {
    samples.hits[0] = centre[i];
    samples.dirs[0] = ray (u, v);
  }
  else
  {
    samples.count = samples.hits.size ();
    for (int sy = 0; sy < ss; ++sy)
      for (int sx = 0; sx < ss; ++sx)
      {
        const std::size_t s = static_cast<std::size_t> (sy) * ss + sx;
        const double ou = (sx + 0.5) / ss - 0.5, ov = (sy + 0.5) / ss - 0.5;
        samples.dirs[s] = ray (u + ou, v + ov);
        samples.hits[s] = (ou == 0.0 && ov == 0.0) ? centre[i] : caster.trace (u, v, origin, samples.dirs[s], true);
      }
  }
  samples.weight = samples.uniform ? static_cast<double> (samples.hits.size ()) : 1.0;
}

PixelIntegral
integratePixel (const SynthScene &scene, const PixelSamples &samples)
{
  PixelIntegral sum;
  for (std::size_t s = 0; s < samples.count; ++s)
  {
    const RayHit &hit = samples.hits[s];
    if (hit.t < 0)
      continue;
    const double z = hit.t * samples.dirs[s].z ();
    sum.zmin = std::min (sum.zmin, z);
    sum.zmax = std::max (sum.zmax, z);
    const int obj = static_cast<int> (scene.primitives[hit.primitive].object);
    sum.counts[obj] += static_cast<int> (samples.weight);
    sum.nearest[obj] = std::min (sum.nearest[obj], z);
    const double amp = samples.weight * scene.primitives[hit.primitive].reflectivity * hit.cos / (hit.t * hit.t);
    sum.amp_sum += amp;
    sum.amp_range += amp * hit.t;
  }
  return sum;
}

/** The noise-free ground truth of pixel i: the object most samples hit (ties: the
  * nearer), the centre ray's depth and primitive, the samples' depth range. */
void
recordGroundTruth (const PixelIntegral &sum, const RayHit &centre, const Eigen::Vector3d &centre_ray, std::size_t i,
                   SynthFrame &frame)
{
  int best = 0;
  for (int o = 1; o < 5; ++o)
    if (sum.counts[o] > sum.counts[best] ||
        (sum.counts[o] == sum.counts[best] && sum.counts[o] > 0 && sum.nearest[o] < sum.nearest[best]))
      best = o;
  frame.object[i] = sum.counts[best] > 0 ? static_cast<SynthObject> (best) : SynthObject::None;
  if (centre.t > 0)
  {
    frame.ideal_z[i] = static_cast<float> (centre.t * centre_ray.z ());
    frame.primitive[i] = centre.primitive;
  }
  if (sum.zmin <= sum.zmax)
  {
    frame.sample_min_z[i] = static_cast<float> (sum.zmin);
    frame.sample_max_z[i] = static_cast<float> (sum.zmax);
  }
}

/** Labels pixel i with the part and person of the surface a hit shows (nothing for the
  * room or a miss). */
void
labelPixel (const SynthScene &scene, const RayHit &hit, std::size_t i, SynthFrame &frame)
{
  if (hit.t < 0)
    return;
  const SynthPrimitive &p = scene.primitives[static_cast<std::size_t> (hit.primitive)];
  const SynthPart part = p.partAt (hit.triangle);
  if (part == SynthPart::None)
    return;
  frame.part_label[i] = static_cast<std::uint8_t> (part);
  frame.person_label[i] = std::max<std::uint8_t> (1, p.person);
}
}  // namespace

void
renderScene (const SynthScene &scene, const SensorModel &model, SynthRng &rng, SynthFrame &frame)
{
  const std::unique_ptr<DepthSensor> sensor = DepthSensor::create (model);
  const int w = model.width, h = model.height;
  const std::size_t n = static_cast<std::size_t> (w) * h;
  const PixelRays ray{model.intrinsics};
  resetFrame (scene, model, frame);

  const RayCaster caster (scene, model);
  const std::vector<RayHit> centre = traceCentreRays (caster, model, ray);

  // Pass 2: each pixel's samples give its ground truth and the sensor's measurement
  // before noise; the labels are those of the surface the measurement shows.
  IdealRender ideal{scene, ray, std::vector<float> (n, kNaN), std::vector<float> (sensor->needsAmplitude () ? n : 0, 0.0f)};
  const int ss = sensor->samplesPerSide ();
  PixelSamples samples (ss);
  PixelMeasurement measured;
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
    {
      const std::size_t i = static_cast<std::size_t> (v) * w + u;
      samplePixel (caster, centre, ray, u, v, w, h, ss, samples);
      const PixelIntegral sum = integratePixel (scene, samples);
      recordGroundTruth (sum, centre[i], ray (u, v), i, frame);
      if (!sensor->measurePixel (samples, sum, centre[i], measured))
        continue;
      ideal.range[i] = measured.range;
      if (!ideal.amplitude.empty ())
        ideal.amplitude[i] = measured.amplitude;
      if (measured.surface)
        labelPixel (scene, *measured.surface, i, frame);
      frame.clean_z[i] = static_cast<float> (measured.range * ray (u, v).z ());
    }

  sensor->measureFrame (ideal, rng, frame);
  clearLabelsWithoutDepth (frame);
}
}  // namespace agex
