#include <agex/detection/fused_candidates.h>

#include <agex/classification/body_part_labeling.h>
#include <agex/common/statistics.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace agex
{
namespace
{
constexpr int kParts = 3;                  // head, hand, foot: the parts a candidate may be
constexpr float kModeReach = 0.10f;        // metres: a mode "near" a candidate
constexpr float kSmallRadius = 0.05f, kLargeRadius = 0.10f;
constexpr float kFarTip = 0.5f;            // metres: distances to mode tips are capped here

/** Adds candidate c unless one within radius exists: then that one also gets c's sources. */
void
addMerged (std::vector<FusedCandidate> &candidates, const FusedCandidate &c, float radius)
{
  for (auto &other : candidates)
    if ((other.position - c.position).norm () < radius)
    {
      other.sources |= c.sources;
      if (other.mode_part < 0 || c.mode_confidence > other.mode_confidence)
      {
        other.mode_part = c.mode_part;
        other.mode_confidence = c.mode_confidence;
      }
      if (other.orientation.squaredNorm () == 0.f)
        other.orientation = c.orientation;
      return;
    }
  candidates.push_back (c);
}

/** The pixel among a mode's support (indices of the organized frame) nearest to p. */
int
nearestPixel (const pcl::PointCloud<pcl::PointXYZ> &cloud, const pcl::Indices &support, const Eigen::Vector3f &p)
{
  int best = -1;
  float best_d = std::numeric_limits<float>::infinity ();
  for (const auto i : support)
    if (i >= 0 && static_cast<std::size_t> (i) < cloud.size () && std::isfinite (cloud[static_cast<std::size_t> (i)].z))
    {
      const float d = (cloud[static_cast<std::size_t> (i)].getVector3fMap () - p).squaredNorm ();
      if (d < best_d)
        best_d = d, best = static_cast<int> (i);
    }
  return best;
}
}  // namespace

int
forestStrideFor (int stride, float fx)
{
  if (stride > 0)
    return stride;
  if (!(fx > 0.f) || !std::isfinite (fx))
    return 1;
  return clampedInt (std::floor (fx / 250.f), 1, 8);  // fx may be far beyond an int
}

bool
labelBodyPixels (const pcl::PointCloud<pcl::PointXYZ>::ConstPtr &cloud, const std::shared_ptr<pcl::Indices> &body,
                 const BodyPartForest::ConstPtr &forest, float fx, float fy, int &stride,
                 pcl::PointCloud<BodyPartLabelPoint> &labels)
{
  BodyPartLabeling<pcl::PointXYZ> labeling;
  labeling.setInputCloud (cloud);
  labeling.setIndices (body);
  labeling.setForest (forest);
  labeling.setFocalLength (fx, fy);
  stride = forestStrideFor (stride, fx);
  labeling.setStride (stride);
  return labeling.compute (labels);
}

bool
labelPersonParts (const DepthPipelineResult &prepared, const BodyPartForest::ConstPtr &forest, float fx, float fy,
                  int stride, pcl::PointCloud<BodyPartLabelPoint> &labels, std::vector<PartMode> &modes,
                  std::pair<double, double> *ms)
{
  const auto start = std::chrono::steady_clock::now ();
  labels.clear ();
  modes.clear ();
  if (!forest || !prepared.filtered || prepared.meshes.empty () || !(fx > 0.f) || !(fy > 0.f))
    return false;
  const std::vector<int> body = prepared.meshIndices ();
  if (!labelBodyPixels (prepared.filtered, std::make_shared<pcl::Indices> (body.begin (), body.end ()), forest, fx, fy,
                        stride, labels))
    return false;
  const auto labelled = std::chrono::steady_clock::now ();
  PartModeEstimation estimation;
  PartModeParams params;
  params.fx = fx;
  params.fy = fy;
  params.pixel_step = stride;  // the representatives only: the other pixels copy them
  estimation.setParams (params);
  const bool found = estimation.compute (labels, body, modes);
  if (ms)
    *ms = {std::chrono::duration<double, std::milli> (labelled - start).count (),
           std::chrono::duration<double, std::milli> (std::chrono::steady_clock::now () - labelled).count ()};
  return found;
}

void
FusedCandidateParams::validate (const std::function<std::string (const std::string &key)> &name) const
{
  std::ostringstream v;
  if (!(merge_radius >= 0.f && merge_radius <= 0.5f))
  {
    v << merge_radius;
    throw std::invalid_argument (name ("merge_radius") + " is " + v.str () + ", outside [0, 0.5] metres");
  }
  if (!(min_mode_confidence >= 0.f && min_mode_confidence <= 1.f))
  {
    v << min_mode_confidence;
    throw std::invalid_argument (name ("min_mode_confidence") + " is " + v.str () + ", outside [0, 1]");
  }
}

std::vector<FusedCandidate>
fusedCandidates (const DepthPipelineResult &prepared, const std::vector<PartMode> &modes,
                 const FusedCandidateParams &params)
{
  std::vector<FusedCandidate> candidates;
  if (!prepared.filtered)
    return candidates;
  const int width = static_cast<int> (prepared.filtered->width);
  for (const auto &p : prepared.interest_points)
  {
    FusedCandidate c;
    c.position = p.getVector3fMap ();
    c.orientation = p.getOrientationVector3fMap ();
    c.index = p.v * width + p.u;
    c.sources = kFromAgex;
    c.agex_rank = p.rank;
    c.geodesic_distance = p.geodesic_distance;
    c.mesh = p.mesh;
    addMerged (candidates, c, params.merge_radius);
  }
  for (const auto &m : modes)
  {
    if (m.part < 0 || m.part >= kParts || !(m.confidence >= params.min_mode_confidence))
      continue;
    // The tip, the peak, and the other end of the part along its direction: a resting hand's
    // direction may point the wrong way (away from the hip it touches), its fingers at the
    // other end.
    int other_end = -1;
    float lowest = std::numeric_limits<float>::infinity ();
    for (const auto i : m.support)
      if (i >= 0 && static_cast<std::size_t> (i) < prepared.filtered->size ())
      {
        const float t = ((*prepared.filtered)[static_cast<std::size_t> (i)].getVector3fMap () - m.position).dot (m.direction);
        if (std::isfinite (t) && t < lowest)
          lowest = t, other_end = static_cast<int> (i);
      }
    for (const int which : {0, 1, 2})
    {
      FusedCandidate c;
      c.index = which == 0 ? m.tip_index : which == 1 ? nearestPixel (*prepared.filtered, m.support, m.position) : other_end;
      if (c.index < 0 || static_cast<std::size_t> (c.index) >= prepared.filtered->size ())
        continue;
      // On the surface the pixel shows: the patch is cut around it.
      c.position = (*prepared.filtered)[static_cast<std::size_t> (c.index)].getVector3fMap ();
      if (!c.position.allFinite ())
        continue;
      c.orientation = which == 2 ? Eigen::Vector3f (-m.direction) : m.direction;
      c.sources = which == 0 ? kFromModeTip : which == 1 ? kFromModePosition : kFromModeEnd;
      c.mode_part = m.part;
      c.mode_confidence = m.confidence;
      addMerged (candidates, c, params.merge_radius);
    }
  }
  return candidates;
}

const std::vector<std::string> &
fusedFeatureNames ()
{
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    const char *parts[] = {"head", "hand", "foot", "other"};
    for (const char *where : {"at", "within_5cm", "within_10cm"})
      for (const char *part : parts)
        n.push_back (std::string ("p_") + part + "_" + where);
    for (int p = 0; p < kParts; ++p)
      n.push_back (std::string ("mode_") + parts[p] + "_confidence_within_10cm");
    for (int p = 0; p < kParts; ++p)
      n.push_back (std::string ("mode_") + parts[p] + "_tip_distance");
    for (int p = 0; p < kParts; ++p)
      n.push_back (std::string ("mode_") + parts[p] + "_direction_agreement");
    for (const char *f : {"from_agex", "agex_rank", "geodesic_distance", "from_mode_tip", "from_mode_position",
                          "from_mode_end", "height_in_mesh", "mesh_height"})
      n.push_back (f);
    return n;
  }();
  return names;
}

int
FusedFeatures::meshOf (const FusedCandidate &candidate) const
{
  if (candidate.mesh >= 0)
    return candidate.mesh;
  const int i = candidate.index;
  return i >= 0 && static_cast<std::size_t> (i) < mesh_of_.size () ? mesh_of_[static_cast<std::size_t> (i)] : -1;
}

FusedFeatures::FusedFeatures (const DepthPipelineResult &prepared, const pcl::PointCloud<BodyPartLabelPoint> &labels,
                              const std::vector<PartMode> &modes, float fx, const Eigen::Vector3f &up)
  : prepared_ (prepared), labels_ (labels), modes_ (modes), fx_ (fx), up_ (up.normalized ())
{
  if (!prepared_.filtered)
    return;
  mesh_of_.assign (prepared_.filtered->size (), -1);
  for (std::size_t m = 0; m < prepared_.meshes.size (); ++m)
  {
    Eigen::Vector2f extent (std::numeric_limits<float>::infinity (), -std::numeric_limits<float>::infinity ());
    for (const auto i : prepared_.meshes[m].indices)
    {
      mesh_of_[static_cast<std::size_t> (i)] = static_cast<int> (m);
      const float h = up_.dot ((*prepared_.filtered)[static_cast<std::size_t> (i)].getVector3fMap ());
      extent = Eigen::Vector2f (std::min (extent.x (), h), std::max (extent.y (), h));
    }
    mesh_extent_.push_back (extent);
  }
}

void
FusedFeatures::meanProbabilities (int index, const Eigen::Vector3f &at, float radius, float *out) const
{
  std::fill (out, out + kLabelPartCount, 0.f);
  if (labels_.empty () || !labels_.isOrganized () || index < 0 || !(at.z () > 0.f) || !(fx_ > 0.f))
    return;
  const int width = static_cast<int> (labels_.width), height = static_cast<int> (labels_.height);
  const int u0 = index % width, v0 = index / width;
  const int r = clampedInt (std::ceil (radius * fx_ / at.z ()), 0, 64);  // a point at 1e-30 m
  const float r2 = radius * radius;
  double sum[kLabelPartCount] = {0.0, 0.0, 0.0, 0.0};
  int count = 0;
  for (int v = std::max (0, v0 - r); v <= std::min (height - 1, v0 + r); ++v)
    for (int u = std::max (0, u0 - r); u <= std::min (width - 1, u0 + r); ++u)
    {
      const BodyPartLabelPoint &q = labels_ (u, v);
      if (q.label == kLabelNone || !std::isfinite (q.z) || (q.getVector3fMap () - at).squaredNorm () > r2)
        continue;
      sum[0] += q.p_head, sum[1] += q.p_hand, sum[2] += q.p_foot, sum[3] += q.p_other;
      ++count;
    }
  for (int p = 0; p < kLabelPartCount && count > 0; ++p)
    out[p] = static_cast<float> (sum[p] / count);
}

void
FusedFeatures::compute (const FusedCandidate &c, float *out) const
{
  float *f = out;
  // The forest at the pixel, then around it.
  std::fill (f, f + kLabelPartCount, 0.f);
  if (!labels_.empty () && c.index >= 0 && static_cast<std::size_t> (c.index) < labels_.size () &&
      labels_[static_cast<std::size_t> (c.index)].label != kLabelNone)
  {
    const auto &q = labels_[static_cast<std::size_t> (c.index)];
    f[0] = q.p_head, f[1] = q.p_hand, f[2] = q.p_foot, f[3] = q.p_other;
  }
  else
    meanProbabilities (c.index, c.position, kSmallRadius, f);  // an unlabelled pixel: its surroundings
  f += kLabelPartCount;
  meanProbabilities (c.index, c.position, kSmallRadius, f);
  f += kLabelPartCount;
  meanProbabilities (c.index, c.position, kLargeRadius, f);
  f += kLabelPartCount;
  // The modes near it.
  float confidence[kParts] = {0.f, 0.f, 0.f}, tip_distance[kParts] = {kFarTip, kFarTip, kFarTip};
  float agreement[kParts] = {0.f, 0.f, 0.f};
  for (const auto &m : modes_)
  {
    if (m.part < 0 || m.part >= kParts)
      continue;
    const float to_tip = (m.tip - c.position).norm ();
    const float to_mode = std::min (to_tip, (m.position - c.position).norm ());
    if (to_mode <= kModeReach)
      confidence[m.part] = std::max (confidence[m.part], m.confidence);
    if (to_tip < tip_distance[m.part])
    {
      tip_distance[m.part] = to_tip;
      const float n = c.orientation.norm () * m.direction.norm ();
      agreement[m.part] = n > 0.f ? c.orientation.dot (m.direction) / n : 0.f;
    }
  }
  for (int p = 0; p < kParts; ++p)
    *f++ = confidence[p];
  for (int p = 0; p < kParts; ++p)
    *f++ = std::isfinite (tip_distance[p]) ? tip_distance[p] : kFarTip;
  for (int p = 0; p < kParts; ++p)
    *f++ = std::isfinite (agreement[p]) ? agreement[p] : 0.f;
  // Its own facts.
  *f++ = (c.sources & kFromAgex) ? 1.f : 0.f;
  *f++ = static_cast<float> (c.agex_rank);
  *f++ = std::isfinite (c.geodesic_distance) ? c.geodesic_distance : 0.f;
  *f++ = (c.sources & kFromModeTip) ? 1.f : 0.f;
  *f++ = (c.sources & kFromModePosition) ? 1.f : 0.f;
  *f++ = (c.sources & kFromModeEnd) ? 1.f : 0.f;
  // Where on its person.
  const int mesh = meshOf (c);
  float relative = 0.5f, extent = 0.f;
  if (mesh >= 0 && static_cast<std::size_t> (mesh) < mesh_extent_.size ())
  {
    const Eigen::Vector2f e = mesh_extent_[static_cast<std::size_t> (mesh)];
    extent = e.y () - e.x ();
    if (extent > 0.f)
      relative = std::clamp ((e.y () - up_.dot (c.position)) / extent, 0.f, 1.f);
  }
  *f++ = relative;
  *f++ = extent;
}

agex::InterestPoint
candidatePoint (const FusedCandidate &c, int width)
{
  agex::InterestPoint p;
  p.getVector3fMap () = c.position;
  p.getOrientationVector3fMap () = c.orientation;
  p.u = width > 0 && c.index >= 0 ? c.index % width : 0;
  p.v = width > 0 && c.index >= 0 ? c.index / width : 0;
  p.rank = c.agex_rank;
  p.mesh = c.mesh;
  p.geodesic_distance = c.geodesic_distance;
  return p;
}
}  // namespace agex
