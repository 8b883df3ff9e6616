// agex::PartBlobEstimation: part proposals as PCL's gpu/people pipeline makes them (label
// smoothing, connected blobs of one label), each placed at the blob's extremity.

#include <agex/classification/part_blobs.h>

#include <agex/common/organized_neighbourhood.h>
#include <agex/common/statistics.h>

#include <pcl/console/print.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace agex
{
namespace
{
void
checkRange (float value, float low, float high, bool low_open, const std::string &key,
            const std::function<std::string (const std::string &)> &name, const char *unit)
{
  if (std::isfinite (value) && (low_open ? value > low : value >= low) && value <= high)
    return;
  std::ostringstream s;
  s << name (key) << " is " << value << ", outside " << (low_open ? "(" : "[") << low << ", " << high << "] " << unit;
  throw std::invalid_argument (s.str ());
}
}  // namespace

void
PartBlobParams::validate (const std::function<std::string (const std::string &key)> &name) const
{
  checkRange (smoothing_radius, 0.f, 0.05f, false, "smoothing_radius", name, "metres");
  checkRange (smoothing_depth_window, 0.f, 2.f, true, "smoothing_depth_window", name, "metres");
  checkRange (connect_distance, 0.f, 0.5f, true, "connect_distance", name, "metres");
  checkRange (min_area, 0.f, 1.f, false, "min_area", name, "m^2");
  checkRange (extremity_depth, 0.f, 0.2f, true, "extremity_depth", name, "metres");
  checkRange (fx, 0.f, 1e6f, true, "fx", name, "pixels");
  checkRange (fy, 0.f, 1e6f, true, "fy", name, "pixels");
  for (int c = 0; c < kLabelPartCount; ++c)
    checkRange (reference_area[static_cast<std::size_t> (c)], 0.f, 10.f, true,
                std::string ("reference_area.") + labelPartName (c), name, "m^2");
}

void
PartBlobEstimation::setParams (const PartBlobParams &params)
{
  params.validate ([] (const std::string &key) { return "PartBlobParams::" + key; });
  params_ = params;
}

bool
PartBlobEstimation::compute (const pcl::PointCloud<BodyPartLabelPoint> &labels, const pcl::Indices &body_pixels,
                             std::vector<PartMode> &blobs) const
{
  blobs.clear ();
  const PartBlobParams &P = params_;
  if (!labels.isOrganized () || labels.width == 0)
  {
    PCL_ERROR ("[agex::PartBlobEstimation::compute] The label cloud must be organized.\n");
    return false;
  }
  const int width = static_cast<int> (labels.width), height = static_cast<int> (labels.height);
  const std::size_t n = labels.size ();
  // slot[i]: the pixel's place among the body's pixels, -1 elsewhere.
  std::vector<int> slot (n, -1), body;
  body.reserve (body_pixels.size ());
  for (const auto i : body_pixels)
  {
    if (i < 0 || static_cast<std::size_t> (i) >= n || slot[static_cast<std::size_t> (i)] >= 0)
      continue;
    const auto &q = labels[static_cast<std::size_t> (i)];
    if (q.label < 0 || !isFinitePoint (q))
      continue;
    slot[static_cast<std::size_t> (i)] = static_cast<int> (body.size ());
    body.push_back (static_cast<int> (i));
  }
  if (body.empty ())
    return true;
  std::sort (body.begin (), body.end ());
  for (std::size_t k = 0; k < body.size (); ++k)
    slot[static_cast<std::size_t> (body[k])] = static_cast<int> (k);

  // Smoothing: a thin part's few stray pixels inside another part (a hand label on the
  // chest, a foot label on the shin) are outvoted, and a part's own pixels are not.
  std::vector<int> part (body.size ());
  for (std::size_t k = 0; k < body.size (); ++k)
  {
    const auto &q = labels[static_cast<std::size_t> (body[k])];
    part[k] = q.label;
    const int r = clampedInt (std::round (P.smoothing_radius * P.fx / q.z), 0, 8);
    if (r == 0)
      continue;
    std::array<int, kLabelPartCount> votes{};
    const int u = body[k] % width, v = body[k] / width;
    for (int dv = -r; dv <= r; ++dv)
      for (int du = -r; du <= r; ++du)
      {
        const int nu = u + du, nv = v + dv;
        if (nu < 0 || nu >= width || nv < 0 || nv >= height)
          continue;
        const auto j = static_cast<std::size_t> (nv * width + nu);
        if (slot[j] < 0)
          continue;
        const auto &o = labels[j];
        if (o.label >= 0 && o.label < kLabelPartCount && std::abs (o.z - q.z) < P.smoothing_depth_window)
          ++votes[static_cast<std::size_t> (o.label)];
      }
    int best = q.label;
    for (int c = 0; c < kLabelPartCount; ++c)
      if (best < 0 || best >= kLabelPartCount || votes[static_cast<std::size_t> (c)] > votes[static_cast<std::size_t> (best)])
        best = c;
    part[k] = best;
  }

  // The body's centre: the centroid of the "other body" pixels (of all without any).
  Eigen::Vector3d other_sum = Eigen::Vector3d::Zero (), all_sum = Eigen::Vector3d::Zero ();
  std::size_t other_count = 0;
  for (std::size_t k = 0; k < body.size (); ++k)
  {
    const Eigen::Vector3d x = labels[static_cast<std::size_t> (body[k])].getVector3fMap ().cast<double> ();
    all_sum += x;
    if (part[k] == kLabelOtherBody)
      other_sum += x, ++other_count;
  }
  const Eigen::Vector3f centre =
      (other_count ? other_sum / static_cast<double> (other_count) : all_sum / static_cast<double> (body.size ())).cast<float> ();
  const float connect2 = P.connect_distance * P.connect_distance;
  const auto linked = [&] (int i, int j) {
    return squaredDistance3D (labels[static_cast<std::size_t> (i)], labels[static_cast<std::size_t> (j)]) < connect2;
  };

  // Blobs: connected pixels of one part, flood-filled in raster order (deterministic).
  std::vector<int> blob_of (body.size (), -1);
  std::vector<std::vector<PartMode>> per_part (kLabelPartCount);
  std::vector<int> stack, members;
  for (std::size_t start = 0; start < body.size (); ++start)
  {
    const int c = part[start];
    if (blob_of[start] >= 0 || c < 0 || c >= kLabelPartCount || !P.parts[static_cast<std::size_t> (c)])
      continue;
    members.clear ();
    stack.assign (1, static_cast<int> (start));
    blob_of[start] = static_cast<int> (start);
    while (!stack.empty ())
    {
      const int k = stack.back ();
      stack.pop_back ();
      members.push_back (k);
      const int i = body[static_cast<std::size_t> (k)], u = i % width, v = i / width;
      for (const auto &o : kAllNeighbours)
      {
        const int nu = u + o[0], nv = v + o[1];
        if (nu < 0 || nu >= width || nv < 0 || nv >= height)
          continue;
        const int j = nv * width + nu, kj = slot[static_cast<std::size_t> (j)];
        if (kj < 0 || blob_of[static_cast<std::size_t> (kj)] >= 0 || part[static_cast<std::size_t> (kj)] != c || !linked (i, j))
          continue;
        blob_of[static_cast<std::size_t> (kj)] = static_cast<int> (start);
        stack.push_back (kj);
      }
    }
    std::sort (members.begin (), members.end ());
    double area = 0.0, mass = 0.0, psum = 0.0;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero ();
    for (const int k : members)
    {
      const auto &q = labels[static_cast<std::size_t> (body[static_cast<std::size_t> (k)])];
      const double a = static_cast<double> (q.z) * q.z / (static_cast<double> (P.fx) * P.fy);
      // A pixel the smoothing gave this part counts with the forest's own probability of it.
      const float p = q.probability (c);
      const double pc = std::isfinite (p) ? p : 0.0;
      area += a;
      mass += a * pc;
      psum += pc;
      mean += q.getVector3fMap ().cast<double> ();
    }
    if (area < P.min_area || !(mass > 0.0))
      continue;
    mean /= static_cast<double> (members.size ());
    // The extremity: the blob's end farthest from the body's centre (the centroid of the
    // "other body" pixels: the torso and limbs), along the direction from there to the
    // blob's centroid: its pixels within extremity_depth of the farthest, and of those the
    // one nearest their median. A single farthest pixel is often a silhouette pixel whose
    // depth mixes the part with the background behind it, 10 cm off.
    const Eigen::Vector3f &base = centre;
    Eigen::Vector3f axis = mean.cast<float> () - base;
    if (!(axis.norm () > 1e-6f))
      continue;
    axis.normalize ();
    std::vector<float> reach (members.size ());
    float farthest = -std::numeric_limits<float>::infinity ();
    for (std::size_t t = 0; t < members.size (); ++t)
    {
      reach[t] = (labels[static_cast<std::size_t> (body[static_cast<std::size_t> (members[t])])].getVector3fMap () - base).dot (axis);
      farthest = std::max (farthest, reach[t]);
    }
    std::array<std::vector<double>, 3> end_coords;
    std::vector<int> end;
    for (std::size_t t = 0; t < members.size (); ++t)
      if (reach[t] >= farthest - P.extremity_depth)
      {
        end.push_back (members[t]);
        const Eigen::Vector3f x = labels[static_cast<std::size_t> (body[static_cast<std::size_t> (members[t])])].getVector3fMap ();
        for (int a = 0; a < 3; ++a)
          end_coords[static_cast<std::size_t> (a)].push_back (x[a]);
      }
    const Eigen::Vector3f end_median = Eigen::Vector3d (median (end_coords[0]), median (end_coords[1]), median (end_coords[2])).cast<float> ();
    int tip = -1;
    float nearest = std::numeric_limits<float>::infinity ();
    for (const int k : end)
    {
      const float d = (labels[static_cast<std::size_t> (body[static_cast<std::size_t> (k)])].getVector3fMap () - end_median).squaredNorm ();
      if (d < nearest)
        nearest = d, tip = k;
    }
    if (tip < 0)
      continue;
    PartMode m;
    m.part = c;
    m.tip_index = body[static_cast<std::size_t> (tip)];
    m.tip = labels[static_cast<std::size_t> (m.tip_index)].getVector3fMap ();
    m.position = m.tip;
    m.mass = static_cast<float> (mass);
    m.confidence = m.mass / (m.mass + P.reference_area[static_cast<std::size_t> (c)]);
    m.mean_probability = static_cast<float> (psum / static_cast<double> (members.size ()));
    m.direction = axis;
    for (const int k : members)
      m.support.push_back (body[static_cast<std::size_t> (k)]);
    per_part[static_cast<std::size_t> (c)].push_back (std::move (m));
  }
  for (auto &found : per_part)
  {
    std::stable_sort (found.begin (), found.end (), [] (const PartMode &a, const PartMode &b) { return a.confidence > b.confidence; });
    blobs.insert (blobs.end (), std::make_move_iterator (found.begin ()), std::make_move_iterator (found.end ()));
  }
  return true;
}
}  // namespace agex
