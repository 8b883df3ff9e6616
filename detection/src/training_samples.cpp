#include <agex/detection/training_samples.h>

#include <agex/features/depth_patch_estimation.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace agex
{
namespace
{
/** Index of the nearest visible tip within radius (any class), or -1. */
int
nearestTip (const Eigen::Vector3f &p, const std::vector<PartLabel> &labels, float radius)
{
  int best = -1;
  float best_d = radius;
  for (std::size_t i = 0; i < labels.size (); ++i)
  {
    if (!labels[i].visible || !labels[i].tip.allFinite ())
      continue;
    const float d = (labels[i].tip - p).norm ();
    if (d <= best_d)
    {
      best_d = d;
      best = static_cast<int> (i);
    }
  }
  return best;
}

/** An interest point at a pixel without orientation: its patch is upright. */
agex::InterestPoint
uprightPoint (const pcl::PointCloud<pcl::PointXYZ> &cloud, int index)
{
  agex::InterestPoint ip;
  ip.getVector3fMap () = cloud[index].getVector3fMap ();
  ip.orientation[0] = ip.orientation[1] = ip.orientation[2] = 0.f;
  ip.u = index % static_cast<int> (cloud.width);
  ip.v = index / static_cast<int> (cloud.width);
  ip.rank = 0;
  return ip;
}

/** count random mesh points farther than min_distance from every tip, as background
  * (label -1); with random_orientation each gets a random in-plane orientation. */
void
appendRandomNegatives (const DepthPipelineResult &prepared, const std::vector<PartLabel> &labels, float min_distance,
                       int count, bool random_orientation, std::mt19937_64 &rng,
                       pcl::PointCloud<agex::InterestPoint> &points, std::vector<int> &point_classes)
{
  const std::vector<int> surface = prepared.meshIndices ();
  const auto &cloud = *prepared.filtered;
  for (int n = 0; n < count && !surface.empty (); ++n)
  {
    const int index = surface[rng () % surface.size ()];
    agex::InterestPoint ip = uprightPoint (cloud, index);
    if (nearestTip (ip.getVector3fMap (), labels, min_distance) >= 0)
      continue;
    if (random_orientation)
    {
      const double angle = (rng () % 3600) * M_PI / 1800.0;
      ip.orientation[0] = static_cast<float> (std::sin (angle));
      ip.orientation[1] = static_cast<float> (std::cos (angle));
    }
    points.push_back (ip);
    point_classes.push_back (-1);
  }
}

/** The patches of points, appended with their classes. */
void
appendPatches (const DepthPipelineResult &prepared, const pcl::PointCloud<agex::InterestPoint> &points,
               const std::vector<int> &point_classes, const PatchGeometry &patch, std::vector<agex::DepthPatch> &patches,
               std::vector<int> &classes)
{
  std::vector<agex::DepthPatch> frame_patches;
  computePatches (prepared, points, patch, frame_patches);
  for (std::size_t i = 0; i < frame_patches.size () && i < point_classes.size (); ++i)
  {
    patches.push_back (frame_patches[i]);
    classes.push_back (point_classes[i]);
  }
}
}  // namespace

void
computePatches (const DepthPipelineResult &prepared, const pcl::PointCloud<agex::InterestPoint> &points,
                const PatchGeometry &params, std::vector<agex::DepthPatch> &patches)
{
  patches.clear ();
  if (points.empty () || !prepared.filtered || !prepared.filtered->isOrganized ())
    return;
  pcl::PointCloud<agex::InterestPoint>::Ptr located (new pcl::PointCloud<agex::InterestPoint> (points));
  agex::DepthPatchEstimation<pcl::PointXYZ, agex::DepthPatch> estimation;
  estimation.setInputCloud (prepared.filtered);
  estimation.setInterestPoints (located);
  estimation.setPatchSize (params.size);
  estimation.setPatchExtent (params.extent);
  estimation.setClampDepth (params.clamp);
  pcl::PointCloud<agex::DepthPatch> out;
  estimation.compute (out);
  patches.assign (out.begin (), out.end ());
}

void
collectTrainingSamples (const DepthPipelineResult &prepared, const std::vector<PartLabel> &labels, float radius,
                        int random_negatives, const PatchGeometry &patch, std::mt19937_64 &rng,
                        std::vector<agex::DepthPatch> &patches, std::vector<int> &classes)
{
  pcl::PointCloud<agex::InterestPoint> points = prepared.interest_points;
  std::vector<int> point_classes;
  for (const auto &p : points)
  {
    const int tip = nearestTip (p.getVector3fMap (), labels, radius);
    point_classes.push_back (tip < 0 ? -1 : static_cast<int> (labels[tip].part));
  }
  // Random surface points: the classifier must also reject what is not an extremum.
  appendRandomNegatives (prepared, labels, 1.5f * radius, random_negatives, true, rng, points, point_classes);
  appendPatches (prepared, points, point_classes, patch, patches, classes);
}

void
collectWindowTrainingSamples (const DepthPipelineResult &prepared, const std::vector<PartLabel> &labels, float radius,
                              int jitter, float jitter_radius, int random_negatives, const PatchGeometry &patch,
                              std::mt19937_64 &rng, std::vector<agex::DepthPatch> &patches, std::vector<int> &classes)
{
  if (!prepared.filtered)
    return;
  const auto &cloud = *prepared.filtered;
  const std::vector<int> surface = prepared.meshIndices ();
  pcl::PointCloud<agex::InterestPoint> points;
  std::vector<int> point_classes;
  for (const auto &l : labels)
  {
    if (!l.visible || !l.tip.allFinite ())
      continue;
    int nearest = -1;
    float nearest_d = radius;
    std::vector<int> near;
    for (const int index : surface)
    {
      const float d = (cloud[index].getVector3fMap () - l.tip).norm ();
      if (d <= nearest_d)
      {
        nearest_d = d;
        nearest = index;
      }
      if (d <= jitter_radius)
        near.push_back (index);
    }
    if (nearest < 0)
      continue;  // the tip's part did not survive the pipeline
    points.push_back (uprightPoint (cloud, nearest));
    point_classes.push_back (static_cast<int> (l.part));
    for (int n = 0; n < jitter && !near.empty (); ++n)
    {
      points.push_back (uprightPoint (cloud, near[rng () % near.size ()]));
      point_classes.push_back (static_cast<int> (l.part));
    }
  }
  appendRandomNegatives (prepared, labels, 1.5f * radius, random_negatives, false, rng, points, point_classes);
  appendPatches (prepared, points, point_classes, patch, patches, classes);
}

void
collectFusedTrainingSamples (const DepthPipelineResult &prepared, const pcl::PointCloud<BodyPartLabelPoint> &labels,
                             const std::vector<PartMode> &modes, float fx, const Eigen::Vector3f &up,
                             const FusedCandidateParams &params, const std::vector<PartLabel> &truth, float radius,
                             const PatchGeometry &geometry, std::vector<agex::DepthPatch> &patches,
                             std::vector<std::vector<float>> &auxiliary, std::vector<int> &classes)
{
  if (!prepared.filtered)
    return;
  const std::vector<FusedCandidate> candidates = fusedCandidates (prepared, modes, params);
  const int width = static_cast<int> (prepared.filtered->width);
  pcl::PointCloud<agex::InterestPoint> points;
  for (const auto &c : candidates)
    points.push_back (candidatePoint (c, width));
  std::vector<agex::DepthPatch> frame_patches;
  computePatches (prepared, points, geometry, frame_patches);
  const FusedFeatures features (prepared, labels, modes, fx, up);
  std::vector<float> aux (fusedFeatureNames ().size ());
  for (std::size_t i = 0; i < frame_patches.size () && i < candidates.size (); ++i)
  {
    features.compute (candidates[i], aux.data ());
    const int tip = nearestTip (candidates[i].position, truth, radius);
    patches.push_back (frame_patches[i]);
    auxiliary.push_back (aux);
    classes.push_back (tip < 0 ? -1 : static_cast<int> (truth[tip].part));
  }
}

std::size_t
keepBackgroundAtMost (float max_ratio, std::mt19937_64 &rng, std::vector<agex::DepthPatch> &patches,
                      std::vector<std::vector<float>> &auxiliary, std::vector<int> &classes)
{
  if (patches.size () != classes.size () || (!auxiliary.empty () && auxiliary.size () != classes.size ()))
    throw std::invalid_argument ("keepBackgroundAtMost: patches, auxiliary features and classes differ in count");
  if (!(max_ratio >= 0.f) || !std::isfinite (max_ratio))
    throw std::invalid_argument ("keepBackgroundAtMost: the ratio must be finite and not negative");
  std::vector<std::size_t> background;
  for (std::size_t i = 0; i < classes.size (); ++i)
    if (classes[i] < 0)
      background.push_back (i);
  const std::size_t positives = classes.size () - background.size ();
  const double allowed = static_cast<double> (max_ratio) * static_cast<double> (positives);
  if (max_ratio == 0.f || static_cast<double> (background.size ()) <= allowed)
    return 0;
  const auto kept_count = static_cast<std::size_t> (allowed);
  std::shuffle (background.begin (), background.end (), rng);
  std::vector<char> keep (classes.size (), 1);
  for (std::size_t i = kept_count; i < background.size (); ++i)
    keep[background[i]] = 0;
  std::size_t out = 0;
  for (std::size_t i = 0; i < classes.size (); ++i)
  {
    if (!keep[i])
      continue;
    if (out != i)
    {
      patches[out] = patches[i];
      classes[out] = classes[i];
      if (!auxiliary.empty ())
        auxiliary[out] = std::move (auxiliary[i]);
    }
    ++out;
  }
  patches.resize (out);
  classes.resize (out);
  if (!auxiliary.empty ())
    auxiliary.resize (out);
  return background.size () - kept_count;
}
}  // namespace agex
