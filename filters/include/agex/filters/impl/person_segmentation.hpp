#pragma once

#include <agex/common/focal_length.h>
#include <agex/common/organized_neighbourhood.h>
#include <agex/common/statistics.h>
#include <agex/filters/floor_removal.h>
#include <agex/filters/person_segmentation.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace agex
{
namespace detail
{
/** One coarse cell per step x step block: the point that stands for it. */
struct PersonGridCell
{
  int pixel = -1;  ///< full-resolution index of its point, -1: no valid point in the block
  float z = 0.f, h = 0.f, lat = 0.f, fwd = 0.f;
  bool valid = false;  ///< has a point above the floor margin
};

/** A cluster's cells whose lateral coordinate lies in [lo, hi). */
struct PersonPart
{
  int cluster = -1;
  float lo = -std::numeric_limits<float>::infinity ();
  float hi = std::numeric_limits<float>::infinity ();
};

/** Why a part is not a person (kPerson: it is). */
enum class PersonVerdict
{
  kPerson,
  kEmpty,
  kTooSmall,
  kTooLow,
  kTooTall,
  kFloating,
  kTooWide,
  kWideTop,
  kTooFlat,  ///< floor-free rule: too little upright extent
  kBehind    ///< floor-free rule: not in front of the background
};

struct PersonPartStats
{
  int cells = 0;
  double area = 0.0;
  float top = -std::numeric_limits<float>::infinity ();
  float bottom = std::numeric_limits<float>::infinity ();
  float lat_min = std::numeric_limits<float>::infinity (), lat_max = -std::numeric_limits<float>::infinity ();
  float fwd_min = std::numeric_limits<float>::infinity (), fwd_max = -std::numeric_limits<float>::infinity ();
  float az_min = std::numeric_limits<float>::infinity (), az_max = -std::numeric_limits<float>::infinity ();
  double lat_sum = 0.0, fwd_sum = 0.0, z_sum = 0.0;
  unsigned border = 0;
  float width = 0.f;         ///< extent of the upright bins along the wider horizontal axis
  float width_across = 0.f;  ///< the same across the view
  float head_width = 0.f;  ///< widest run of lateral bins holding crown cells
  int outline = 0, outline_background = 0;
  bool outlined = false;  ///< outline counted
  int base = 0, base_supported = 0;  ///< lowest cells, and those standing on something
  int crown = 0, crown_hidden = 0;    ///< top cells, and those with something nearer above
  float bin = 0.05f;
  std::vector<float> profile;  ///< highest point per lateral bin from lat_min (-inf: empty)
  std::vector<int> column;     ///< cells per lateral bin
  std::vector<float> fill;     ///< cells per image column in each lateral bin

  float latMean () const { return cells ? static_cast<float> (lat_sum / cells) : 0.f; }
  float fwdMean () const { return cells ? static_cast<float> (fwd_sum / cells) : 0.f; }
  float zMean () const { return cells ? static_cast<float> (z_sum / cells) : 0.f; }
};

/** A candidate person: parts of clusters, what they measure and what they were found to be. */
struct PersonCandidate
{
  std::vector<PersonPart> parts;
  PersonPartStats stats;
  PersonVerdict verdict = PersonVerdict::kEmpty;
  bool split = false;
  bool hidden = false;
  int pieces = 1;
};

/** Where to cut a cluster between two heads, and how deep the valley between them is. */
struct PersonCut
{
  float depth, at;
};

/** What one segment () hands from step to step, so that the steps need no long parameter
  * lists: the frame's geometry, the coarse grid, its clusters and whose each cell became. */
struct PersonScan
{
  int width = 0, height = 0;                      ///< full resolution
  float fx = 0.f, fy = 0.f;                       ///< focal lengths used
  int step = 1, cw = 0, ch = 0;                   ///< coarse step, grid columns and rows
  float coarse_spacing = 0.f;                     ///< cell spacing per metre of depth
  float coarse_area = 0.f;                        ///< cell area per square metre of depth
  std::vector<unsigned char> selected;            ///< the input indices as a mask; empty: all
  std::vector<PersonGridCell> grid;
  pcl::Indices cell_pixels;                       ///< the cells' points
  bool with_floor = false;
  Eigen::Vector3f normal = Eigen::Vector3f::Zero ();   ///< up: the floor's normal, or the up axis
  float offset = 0.f;                                  ///< height = normal . p + offset
  Eigen::Vector3f lateral = Eigen::Vector3f::Zero ();  ///< ground axis: the camera's x laid on the floor
  Eigen::Vector3f forward = Eigen::Vector3f::Zero ();  ///< ground axis: away from the camera
  std::vector<int> cluster_of;                    ///< cluster of each cell, -1: none
  std::vector<int> cluster_start, cluster_cells;  ///< cluster k: cluster_cells[start[k], start[k + 1])
  std::vector<int> cell_person;                   ///< person of each cell after merging, -1: nobody
};

/** The blocks one person's pixels are looked for in, with the depth range of the person's
  * cells around each; kept between persons so that the grid-sized arrays are set up once. */
struct PersonBlocks
{
  std::vector<int> stamp;  ///< the person whose blocks last included the cell
  std::vector<float> zlo, zhi;
  std::vector<int> cells;  ///< this person's blocks
  float floor_level = 0.f;   ///< height of the floor under this person, from its floor cells
  std::vector<float> levels;  ///< the floor cells' heights it is the median of
};

/** One person's full-resolution pixels. */
struct PersonPixels
{
  std::vector<int> indices;
  int count = 0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero ();
};

inline float
personDepthGap (float z, float spacing_per_metre, float slope, float noise, float min_gap)
{
  return std::max (min_gap, slope * spacing_per_metre * z + 3.f * noise * z * z);
}

/** The noise of a height measured at depth z, rel metres above or below the camera along
  * the up axis: depth noise moves a point along its viewing ray, which changes its height by
  * rel / z of the depth error (a floor 1 m below the camera seen 4 m away: a quarter of it;
  * the top of a head near the camera's height: almost nothing). */
inline float
heightNoise (float noise, float z, float rel)
{
  return noise * z * std::abs (rel);  // noise(z) = noise z^2, times rel / z
}

/** What a plane found among the cells looks like from all of them: how far its inliers
  * spread on it (the smaller standard deviation of their positions in the plane: a strip,
  * such as a body's lower edge cut by the image, has almost none), how many cells lie on it
  * and how many under it. */
struct FloorExtent
{
  float spread = 0.f;  ///< metres
  int inliers = 0;     ///< cells within the distance of the plane
  int below = 0;       ///< cells below it by more than the floor search's limit
};

template <typename PointT> FloorExtent
floorExtent (const pcl::PointCloud<PointT> &cloud, const pcl::Indices &indices, const Eigen::Vector4f &plane,
             float distance)
{
  const Eigen::Vector3f normal = plane.head<3> ();
  Eigen::Vector3f a = Eigen::Vector3f::UnitX () - normal.x () * normal;
  if (a.norm () < 1e-3f)
    a = Eigen::Vector3f::UnitZ () - normal.z () * normal;
  a.normalize ();
  const Eigen::Vector3f b = normal.cross (a);
  Eigen::Vector2d sum = Eigen::Vector2d::Zero ();
  Eigen::Matrix2d products = Eigen::Matrix2d::Zero ();
  FloorExtent extent;
  // agex::FloorRemoval's limit for "under the plane".
  const float below_limit = -std::max (0.10f, 3.f * distance);
  for (const auto i : indices)
  {
    const Eigen::Vector3f p = cloud[i].getVector3fMap ();
    const float h = normal.dot (p) + plane[3];
    extent.below += h < below_limit;
    if (std::abs (h) >= distance)
      continue;
    const Eigen::Vector2d q (a.dot (p), b.dot (p));
    sum += q;
    products += q * q.transpose ();
    ++extent.inliers;
  }
  if (extent.inliers < 3)
    return extent;
  const Eigen::Vector2d mean = sum / extent.inliers;
  const Eigen::Matrix2d covariance = products / extent.inliers - mean * mean.transpose ();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver (covariance, Eigen::EigenvaluesOnly);
  extent.spread = static_cast<float> (std::sqrt (std::max (0.0, solver.eigenvalues ()[0])));
  return extent;
}

/** The bin of value in n bins of size bin from lo, clamped to [0, n): a coordinate far from
  * lo (or an infinite or NaN difference) must not overflow the int. */
inline int
binIndex (float value, float lo, float bin, int n)
{
  return clampedInt ((value - lo) / bin, 0, n - 1);
}

/** Extent of the bins whose height span reaches min_span (0 if none). */
inline float
uprightExtent (const std::vector<float> &lo, const std::vector<float> &hi, float bin, float min_span)
{
  int first = -1, last = -1;
  for (int b = 0; b < static_cast<int> (lo.size ()); ++b)
    if (hi[b] - lo[b] >= min_span)
    {
      if (first < 0)
        first = b;
      last = b;
    }
  return first < 0 ? 0.f : static_cast<float> (last - first + 1) * bin;
}

/** Calls f (part, cell, grid cell) for each cell of the parts, part by part in cluster order:
  * the order sums are taken in, so it must not change. */
template <typename F> void
forEachPartCell (const PersonScan &scan, const std::vector<PersonPart> &parts, F &&f)
{
  for (const auto &part : parts)
    for (int k = scan.cluster_start[part.cluster]; k < scan.cluster_start[part.cluster + 1]; ++k)
    {
      const int c = scan.cluster_cells[k];
      const PersonGridCell &g = scan.grid[c];
      if (g.lat < part.lo || g.lat >= part.hi)
        continue;
      f (part, c, g);
    }
}

/** Calls f (neighbour, diagonal) for each of the 8 neighbours of cell c inside the grid. */
template <typename F> void
forEachNeighbourCell (const PersonScan &scan, int c, F &&f)
{
  const int cu = c % scan.cw, cv = c / scan.cw;
  for (const auto &d : kAllNeighbours)
  {
    const int nu = cu + d[0], nv = cv + d[1];
    if (nu < 0 || nu >= scan.cw || nv < 0 || nv >= scan.ch)
      continue;
    f (nv * scan.cw + nu, d[0] != 0 && d[1] != 0);
  }
}

inline bool
inPersonParts (const PersonScan &scan, const std::vector<PersonPart> &parts, int c)
{
  for (const auto &part : parts)
    if (scan.cluster_of[c] == part.cluster && scan.grid[c].lat >= part.lo && scan.grid[c].lat < part.hi)
      return true;
  return false;
}

inline void
claimPersonCells (PersonScan &scan, const std::vector<PersonPart> &parts, int k)
{
  forEachPartCell (scan, parts, [&] (const PersonPart &, int c, const PersonGridCell &) { scan.cell_person[c] = k; });
}

/** Drops the candidates marked used, the rest in their order. */
inline void
dropUsed (std::vector<PersonCandidate> &candidates, const std::vector<unsigned char> &used)
{
  std::size_t kept = 0;
  for (std::size_t i = 0; i < candidates.size (); ++i)
    if (!used[i] && kept++ != i)  // never moved onto itself, which would empty it
      candidates[kept - 1] = std::move (candidates[i]);
  candidates.resize (kept);
}

/** Marks the persons whose cells touch the parts in the image. */
inline void
touchedPersons (const PersonScan &scan, const std::vector<PersonPart> &parts, std::vector<unsigned char> &touches)
{
  std::fill (touches.begin (), touches.end (), 0);
  forEachPartCell (scan, parts, [&] (const PersonPart &, int c, const PersonGridCell &) {
    forEachNeighbourCell (scan, c, [&] (int j, bool) {
      if (scan.cell_person[j] >= 0)
        touches[scan.cell_person[j]] = 1;
    });
  });
}

inline float
groundDistance (const PersonPartStats &a, const PersonPartStats &b)
{
  return std::hypot (a.latMean () - b.latMean (), a.fwdMean () - b.fwdMean ());
}

/** Whether one of the three pixels above pixel i carries label (those rows are done when
  * pixel i is looked at: the pixels are taken row by row). */
inline bool
belowPerson (const pcl::PointCloud<pcl::Label> &labels, int i, int width, std::uint32_t label)
{
  if (i < width)
    return false;
  const int u = i % width, above = i - width;
  return labels[above].label == label || (u > 0 && labels[above - 1].label == label) ||
         (u + 1 < width && labels[above + 1].label == label);
}

/** Person k's blocks: its cells and the free cells next to them (a pixel of a free block may
  * still be the person's), in raster order so that the pixels come out sorted. Returns
  * whether any of the parts is bounded by a cut (then each pixel is tested against it). */
inline bool
personBlocks (const PersonScan &scan, const std::vector<PersonPart> &parts, int k, PersonBlocks &blocks)
{
  blocks.cells.clear ();
  bool bounded = false;
  for (const auto &part : parts)
  {
    bounded = bounded || std::isfinite (part.lo) || std::isfinite (part.hi);
    for (int q = scan.cluster_start[part.cluster]; q < scan.cluster_start[part.cluster + 1]; ++q)
    {
      const int c = scan.cluster_cells[q];
      if (scan.cell_person[c] != k)
        continue;
      const float z = scan.grid[c].z;
      const int cu = c % scan.cw, cv = c / scan.cw;
      for (int dv = -1; dv <= 1; ++dv)
        for (int du = -1; du <= 1; ++du)
        {
          const int nu = cu + du, nv = cv + dv;
          if (nu < 0 || nu >= scan.cw || nv < 0 || nv >= scan.ch)
            continue;
          const int j = nv * scan.cw + nu;
          if (scan.cell_person[j] >= 0 && scan.cell_person[j] != k)
            continue;
          if (blocks.stamp[j] != k)
          {
            blocks.stamp[j] = k;
            blocks.zlo[j] = blocks.zhi[j] = z;
            blocks.cells.push_back (j);
          }
          else
          {
            blocks.zlo[j] = std::min (blocks.zlo[j], z);
            blocks.zhi[j] = std::max (blocks.zhi[j], z);
          }
        }
    }
  }
  std::sort (blocks.cells.begin (), blocks.cells.end ());
  return bounded;
}
}  // namespace detail
}  // namespace agex

template <typename PointT> bool
agex::PersonSegmentation<PointT>::validParameters () const
{
  auto positive = [] (float v) { return std::isfinite (v) && v > 0.f; };
  auto non_negative = [] (float v) { return std::isfinite (v) && v >= 0.f; };
  return up_.allFinite () && up_.norm () > 0.f && floor_max_tilt_deg_ >= 0.f && floor_max_tilt_deg_ < 90.f &&
         positive (floor_distance_) && non_negative (min_floor_spread_) && non_negative (fx_) &&
         non_negative (fy_) && coarse_step_ >= 0 && coarse_step_ <= 64 && non_negative (depth_noise_) &&
         non_negative (max_slope_) && positive (min_gap_) &&
         non_negative (min_top_) && positive (max_top_) && min_top_ < max_top_ && non_negative (max_bottom_) &&
         positive (max_width_) && non_negative (min_area_) && positive (crown_drop_) && positive (max_crown_ratio_) &&
         non_negative (min_crown_width_) &&
         positive (min_head_distance_) && positive (min_valley_depth_) && max_narrowing_ > 0.f &&
         max_narrowing_ <= 1.f && non_negative (merge_reach_) &&
         non_negative (merge_distance_) && non_negative (fallback_min_extent_) && min_background_fraction_ >= 0.f &&
         min_background_fraction_ <= 1.f && positive (hand_area_) && non_negative (min_hand_pixels_) &&
         positive (hidden_min_area_);
}

template <typename PointT> std::vector<bool>
agex::PersonSegmentation<PointT>::getTooFar () const
{
  std::vector<bool> far;
  far.reserve (infos_.size ());
  for (const auto &info : infos_)
    far.push_back (info.too_far);
  return far;
}

template <typename PointT> void
agex::PersonSegmentation<PointT>::segment (std::vector<pcl::PointIndices> &persons)
{
  // The labels are needed inside; kept between calls, a frame's worth of them is not
  // allocated (and paged in) anew for every frame.
  segment (scratch_labels_, persons);
}

template <typename PointT> bool
agex::PersonSegmentation<PointT>::validInput () const
{
  if (!input_->isOrganized ())
  {
    PCL_ERROR ("[agex::%s::segment] The input cloud is not organized (height %u); persons are found on the "
               "pixel grid.\n", getClassName ().c_str (), input_->height);
    return false;
  }
  if (!validParameters ())
  {
    PCL_ERROR ("[agex::%s::segment] Invalid parameters: every length, area and count must be finite and "
               "non-negative (floor distance, minimum gap, crown, split and hand limits, maximum top and width "
               "positive), the minimum top below the maximum, the floor tilt under 90 degrees, the coarse step "
               "0-64, the narrowing in (0, 1], the background fraction in [0, 1] and the up axis non-zero.\n",
               getClassName ().c_str ());
    return false;
  }
  if (floor_given_ && !(given_floor_.allFinite () && given_floor_.head<3> ().norm () > 0.f))
  {
    PCL_ERROR ("[agex::%s::segment] The floor plane (%g, %g, %g, %g) has no finite, non-zero normal.\n",
               getClassName ().c_str (), given_floor_[0], given_floor_[1], given_floor_[2], given_floor_[3]);
    return false;
  }
  return true;
}

template <typename PointT> void
agex::PersonSegmentation<PointT>::segment (pcl::PointCloud<pcl::Label> &labels, std::vector<pcl::PointIndices> &persons)
{
  persons.clear ();
  labels.clear ();
  infos_.clear ();
  floor_found_ = false;
  floor_plane_.setZero ();
  used_fx_ = used_fy_ = 0.f;
  used_step_ = 0;
  if (!initCompute ())
    return;
  if (!validInput ())
  {
    deinitCompute ();
    return;
  }

  const PointCloud &cloud = *input_;
  const int n = static_cast<int> (cloud.size ());
  labels.width = cloud.width;
  labels.height = cloud.height;
  labels.is_dense = cloud.is_dense;
  labels.header = cloud.header;
  pcl::Label nobody;
  nobody.label = kUnlabelled;
  labels.points.assign (n, nobody);

  detail::PersonScan scan;
  scan.width = static_cast<int> (cloud.width);
  scan.height = static_cast<int> (cloud.height);
  if (!fake_indices_)
  {
    scan.selected.assign (n, 0);
    for (const auto i : *indices_)
      if (i >= 0 && i < n)
        scan.selected[i] = 1;
  }
  estimateFocalLengths (scan);
  used_fx_ = scan.fx;
  used_fy_ = scan.fy;
  if (!saneFocalLength (scan.fx) || !saneFocalLength (scan.fy))
  {
    // Cells, bins and windows are metric sizes over pixels: such a frame has none that fit.
    PCL_ERROR ("[agex::%s::segment] Focal lengths %g, %g px (%s) lie outside %g to %g px: the points are not a "
               "camera's at metric scale (coordinates far too large or small); no persons.\n",
               getClassName ().c_str (), scan.fx, scan.fy,
               fx_ > 0.f && fy_ > 0.f ? "as given" : "estimated from the points", kMinFocalLength, kMaxFocalLength);
    deinitCompute ();
    return;
  }
  const bool any_cell = buildCoarseGrid (scan);
  used_step_ = scan.step;
  if (!any_cell)
  {
    deinitCompute ();
    return;
  }
  findFloor (scan);
  placeCells (scan);
  clusterCells (scan);
  std::vector<detail::PersonCandidate> people, leftovers;
  findCandidates (scan, people, leftovers);
  mergePersonLike (scan, people);
  mergeHiddenPieces (scan, people, leftovers);
  mergePieces (scan, people, leftovers);
  findHiddenPersons (scan, people, leftovers);
  std::vector<detail::PersonPixels> pixels;
  takePixels (scan, people, labels, pixels);
  describePersons (scan, people, pixels, labels, persons);
  deinitCompute ();
}

template <typename PointT> bool
agex::PersonSegmentation<PointT>::usable (const detail::PersonScan &scan, int i) const
{
  const PointT &p = (*input_)[i];
  return (fake_indices_ || scan.selected[i]) && std::isfinite (p.x) && std::isfinite (p.y) && std::isfinite (p.z) &&
         p.z > 0.f;
}

template <typename PointT> float
agex::PersonSegmentation<PointT>::floorMargin (const detail::PersonScan &scan, float z, float h) const
{
  return std::max (floor_distance_, 3.f * detail::heightNoise (depth_noise_, z, h - scan.offset));
}

template <typename PointT> bool
agex::PersonSegmentation<PointT>::connected (const detail::PersonScan &scan, const detail::PersonGridCell &a,
                                             const detail::PersonGridCell &b, bool diagonal) const
{
  const float zm = 0.5f * (a.z + b.z);
  const float spacing = diagonal ? scan.coarse_spacing * 1.41421356f : scan.coarse_spacing;
  return std::abs (a.z - b.z) <= detail::personDepthGap (zm, spacing, max_slope_, depth_noise_, min_gap_);
}

/** Focal lengths: u = fx x / z + cx, fitted by least squares on a lattice of pixels (the
  * cell size and every pixel count depend on them, and a PCD carries none). */
template <typename PointT> void
agex::PersonSegmentation<PointT>::estimateFocalLengths (detail::PersonScan &scan) const
{
  const PointCloud &cloud = *input_;
  const int width = scan.width, height = scan.height;
  const int n = static_cast<int> (cloud.size ());
  float fx = fx_, fy = fy_;
  if (!(fx > 0.f) || !(fy > 0.f))
  {
    const int stride = std::max (1, static_cast<int> (std::lround (std::sqrt (n / 4800.0))));
    double m = 0, su = 0, sa = 0, saa = 0, sua = 0, sv = 0, sb = 0, sbb = 0, svb = 0;
    for (int v = stride / 2; v < height; v += stride)
      for (int u = stride / 2; u < width; u += stride)
      {
        const int i = v * width + u;
        if (!usable (scan, i))
          continue;
        const PointT &p = cloud[i];
        const double a = p.x / p.z, b = p.y / p.z;
        m += 1, su += u, sa += a, saa += a * a, sua += u * a;
        sv += v, sb += b, sbb += b * b, svb += v * b;
      }
    const double var_a = m > 0 ? saa - sa * sa / m : 0.0, var_b = m > 0 ? sbb - sb * sb / m : 0.0;
    const double efx = var_a > 1e-12 ? (sua - su * sa / m) / var_a : 0.0;
    const double efy = var_b > 1e-12 ? (svb - sv * sb / m) / var_b : 0.0;
    // Too few or degenerate points: the Kinect's 525 px at 640 columns, scaled. A fit far
    // below a pixel is kept: such points are not at metric scale, and segment () says so.
    const double fallback = 525.0 * width / 640.0;
    auto fitted = [&] (double e) {
      return static_cast<float> (m >= 16 && std::isfinite (e) && (e > 1.0 || (e > 0.0 && e < kMinFocalLength))
                                     ? e
                                     : fallback);
    };
    if (!(fx > 0.f))
      fx = fitted (efx);
    if (!(fy > 0.f))
      fy = fitted (efy);
  }
  scan.fx = fx;
  scan.fy = fy;
}

/** 1. The coarse grid: the block's centre pixel, or else the first usable centre of its
  * quarters (a block without either is empty: its pixels may still join a neighbour's
  * person at full resolution). Finding people on the cells keeps the cost the same at any
  * resolution. Returns false when no cell has a point. */
template <typename PointT> bool
agex::PersonSegmentation<PointT>::buildCoarseGrid (detail::PersonScan &scan) const
{
  const int width = scan.width, height = scan.height;
  const float fx = scan.fx, fy = scan.fy;
  // The automatic step is bounded as a given one is (0-64), before it becomes an int.
  const int step = coarse_step_ > 0
                       ? coarse_step_
                       : clampedInt (std::round (kAutoCellAngle * std::min (fx, fy)), 1, 64);
  scan.step = step;
  const int cw = (width + step - 1) / step, ch = (height + step - 1) / step;
  scan.cw = cw;
  scan.ch = ch;
  scan.grid.assign (static_cast<std::size_t> (cw) * ch, detail::PersonGridCell ());
  scan.cell_pixels.clear ();
  for (int cv = 0; cv < ch; ++cv)
    for (int cu = 0; cu < cw; ++cu)
    {
      const int u0 = cu * step, v0 = cv * step;
      const int u1 = std::min (width, u0 + step), v1 = std::min (height, v0 + step);
      const int bu = u1 - u0, bv = v1 - v0;
      int pixel = (v0 + bv / 2) * width + u0 + bu / 2;
      if (!usable (scan, pixel))
      {
        pixel = -1;
        for (int q = 0; q < 4 && pixel < 0; ++q)
        {
          const int candidate = (v0 + (q / 2 * 2 + 1) * bv / 4) * width + u0 + (q % 2 * 2 + 1) * bu / 4;
          if (usable (scan, candidate))
            pixel = candidate;
        }
      }
      scan.grid[cv * cw + cu].pixel = pixel;
      if (pixel >= 0)
        scan.cell_pixels.push_back (pixel);
    }
  const float per_pixel = 1.f / std::min (fx, fy);  // spacing of adjacent pixels per metre of depth
  scan.coarse_spacing = step * per_pixel;
  scan.coarse_area = scan.coarse_spacing * scan.coarse_spacing;
  return !scan.cell_pixels.empty ();
}

/** RANSAC's sample for the floor: the cells whose surface (from the cells to the right and
  * below) faces up within the tilt limit and 20 degrees more. The floor is most of them, so
  * RANSAC needs a few dozen draws instead of a thousand. */
template <typename PointT> pcl::IndicesPtr
agex::PersonSegmentation<PointT>::levelCells (const detail::PersonScan &scan) const
{
  const PointCloud &cloud = *input_;
  const int cw = scan.cw, ch = scan.ch;
  pcl::IndicesPtr level (new pcl::Indices);
  const Eigen::Vector3f up = up_.normalized ();
  const float min_cos = std::cos (std::min (89.f, floor_max_tilt_deg_ + 20.f) * static_cast<float> (M_PI) / 180.f);
  const float spacing = scan.step / std::min (scan.fx, scan.fy);
  for (int cv = 0; cv + 1 < ch; ++cv)
    for (int cu = 0; cu + 1 < cw; ++cu)
    {
      const int c = cv * cw + cu;
      const int r = scan.grid[c].pixel, d = scan.grid[c + cw].pixel, q = scan.grid[c + 1].pixel;
      if (r < 0 || d < 0 || q < 0)
        continue;
      const Eigen::Vector3f p0 = cloud[r].getVector3fMap ();
      const Eigen::Vector3f right = cloud[q].getVector3fMap () - p0, down = cloud[d].getVector3fMap () - p0;
      // A floor seen at a grazing angle changes depth fast from row to row: no gap test.
      if (std::abs (right.z ()) > detail::personDepthGap (p0.z (), spacing, max_slope_, depth_noise_, min_gap_))
        continue;
      const Eigen::Vector3f facing = right.cross (down);
      const float norm = facing.norm ();
      if (norm > 0.f && std::abs (facing.dot (up)) >= min_cos * norm)
        level->push_back (r);
    }
  return level;
}

/** 2. The floor: given, or searched for among the cells and kept only if its inliers spread
  * over an area (a level strip, such as a torso's lower edge cut off by the image, is no floor). */
template <typename PointT> void
agex::PersonSegmentation<PointT>::findFloor (detail::PersonScan &scan)
{
  if (floor_given_)
  {
    floor_plane_ = given_floor_ / given_floor_.head<3> ().norm ();
    if (floor_plane_.head<3> ().dot (up_) < 0.f)
      floor_plane_ = -floor_plane_;  // heights grow upwards whichever way the plane was written
    floor_found_ = true;
    return;
  }
  const pcl::IndicesPtr level = levelCells (scan);
  agex::FloorRemoval<PointT> floor;
  floor.setInputCloud (input_);
  floor.setIndices (level);
  floor.setUpAxis (up_);
  floor.setMaxTilt (floor_max_tilt_deg_);
  floor.setDistanceThreshold (floor_distance_);
  // About 2,000 points: plenty for a plane, and RANSAC's cost grows with them.
  floor.setSampleStride (std::max (1, static_cast<int> (level->size () / 2000)));
  // The floor far away may be seen in a few rows of cells only (a person at 4-6 m, a
  // camera low or tilted up): a few cells are enough for a plane, and the rules below,
  // judged on all cells, tell a floor from level bits of a body or of furniture.
  floor.setMinInliers (kMinFloorCells);
  pcl::Indices above;
  floor.filter (above);
  if (floor.getFloorFound ())
  {
    // FloorRemoval looks under a plane among its upward-facing sample only; nothing of the
    // frame may lie under a floor (the upright body under the level top of a shoulder or
    // forearm does).
    const detail::FloorExtent extent =
        detail::floorExtent (*input_, scan.cell_pixels, floor.getFloorPlane (), floor_distance_);
    floor_found_ = extent.spread >= min_floor_spread_ && 4 * extent.below <= extent.inliers;
  }
  if (floor_found_)
    floor_plane_ = floor.getFloorPlane ();
}

/** Heights and ground coordinates of the cells: every rule below is in metres above the
  * floor (or along the up axis without one) and on the ground. Cells within the floor
  * margin are nobody's. */
template <typename PointT> void
agex::PersonSegmentation<PointT>::placeCells (detail::PersonScan &scan) const
{
  const PointCloud &cloud = *input_;
  scan.with_floor = floor_found_;
  Eigen::Vector3f normal;
  float offset = 0.f;
  if (scan.with_floor)
  {
    normal = floor_plane_.head<3> ();
    offset = floor_plane_[3];
  }
  else
    normal = up_.normalized ();
  // Ground axes: lateral (the camera's x laid on the floor) and forward.
  Eigen::Vector3f lateral = Eigen::Vector3f::UnitX () - normal.x () * normal;
  if (lateral.norm () < 1e-3f)
    lateral = Eigen::Vector3f::UnitZ () - normal.z () * normal;
  lateral.normalize ();
  const Eigen::Vector3f forward = normal.cross (lateral);
  scan.normal = normal;
  scan.offset = offset;
  scan.lateral = lateral;
  scan.forward = forward;

  for (auto &cell : scan.grid)
  {
    if (cell.pixel < 0)
      continue;
    const PointT &p = cloud[cell.pixel];
    const Eigen::Vector3f xyz = p.getVector3fMap ();
    cell.z = p.z;
    cell.h = normal.dot (xyz) + offset;
    cell.lat = lateral.dot (xyz);
    cell.fwd = forward.dot (xyz);
    cell.valid = !scan.with_floor || cell.h >= floorMargin (scan, p.z, cell.h);
  }
}

/** 3. Clusters of connected cells, seeded in raster order: the later steps take the clusters
  * in this order (a pixel two persons could claim goes to the first), so it is part of the
  * result. */
template <typename PointT> void
agex::PersonSegmentation<PointT>::clusterCells (detail::PersonScan &scan) const
{
  const std::vector<detail::PersonGridCell> &grid = scan.grid;
  std::vector<int> &cluster_of = scan.cluster_of, &cluster_start = scan.cluster_start;
  std::vector<int> &cluster_cells = scan.cluster_cells;
  cluster_of.assign (grid.size (), -1);
  cluster_start.assign (1, 0);
  cluster_cells.clear ();
  cluster_cells.reserve (grid.size ());
  for (int seed = 0; seed < static_cast<int> (grid.size ()); ++seed)
  {
    if (!grid[seed].valid || cluster_of[seed] >= 0)
      continue;
    const int id = static_cast<int> (cluster_start.size ()) - 1;
    std::size_t head = cluster_cells.size ();
    cluster_cells.push_back (seed);
    cluster_of[seed] = id;
    for (; head < cluster_cells.size (); ++head)
    {
      const int c = cluster_cells[head];
      detail::forEachNeighbourCell (scan, c, [&] (int j, bool diagonal) {
        if (!grid[j].valid || cluster_of[j] >= 0 || !connected (scan, grid[c], grid[j], diagonal))
          return;
        cluster_of[j] = id;
        cluster_cells.push_back (j);
      });
    }
    cluster_start.push_back (static_cast<int> (cluster_cells.size ()));
  }
}

/** Statistics of a set of parts (one person, or a candidate): what every rule is judged on. */
template <typename PointT> void
agex::PersonSegmentation<PointT>::measure (const detail::PersonScan &scan, const std::vector<detail::PersonPart> &parts,
                                           detail::PersonPartStats &s) const
{
  s = detail::PersonPartStats ();
  detail::forEachPartCell (scan, parts, [&] (const detail::PersonPart &, int c, const detail::PersonGridCell &g) {
    ++s.cells;
    s.area += scan.coarse_area * g.z * g.z;
    s.top = std::max (s.top, g.h);
    s.bottom = std::min (s.bottom, g.h);
    s.lat_min = std::min (s.lat_min, g.lat);
    s.lat_max = std::max (s.lat_max, g.lat);
    s.fwd_min = std::min (s.fwd_min, g.fwd);
    s.fwd_max = std::max (s.fwd_max, g.fwd);
    const float az = g.lat / std::max (g.fwd, 0.05f);
    s.az_min = std::min (s.az_min, az);
    s.az_max = std::max (s.az_max, az);
    s.lat_sum += g.lat;
    s.fwd_sum += g.fwd;
    s.z_sum += g.z;
    const int cu = c % scan.cw, cv = c / scan.cw;
    s.border |= (cu == 0 ? PersonInfo::kLeft : 0u) | (cu == scan.cw - 1 ? PersonInfo::kRight : 0u) |
                (cv == 0 ? PersonInfo::kTop : 0u) | (cv == scan.ch - 1 ? PersonInfo::kBottom : 0u);
  });
  if (!s.cells)
    return;
  if (s.area < minPersonArea (s))
  {
    // Too small for anyone (a possible piece of someone): the bins are not needed.
    s.width = s.width_across = std::max (s.lat_max - s.lat_min, s.fwd_max - s.fwd_min);
    return;
  }
  measureBins (scan, parts, s);
}

/** Bins across (lat) and along (fwd) the view: the upright extent (arms held out do not
  * widen a person, a wall seen end-on does), the crown (the cells within the crown drop,
  * plus twice the noise, of the top), what the crown and the base border on, and the height
  * profile the split looks for heads in. */
template <typename PointT> void
agex::PersonSegmentation<PointT>::measureBins (const detail::PersonScan &scan,
                                               const std::vector<detail::PersonPart> &parts,
                                               detail::PersonPartStats &s) const
{
  constexpr float kInf = std::numeric_limits<float>::infinity ();
  s.bin = std::max (0.05f, 1.5f * scan.coarse_spacing * s.zMean ());
  const float max_extent = 8.f;
  auto bins = [&] (float lo, float hi) {
    return static_cast<int> (std::min (max_extent, hi - lo) / s.bin) + 1;
  };
  const int nlat = bins (s.lat_min, s.lat_max), nfwd = bins (s.fwd_min, s.fwd_max);
  std::vector<float> lat_lo (nlat, kInf), lat_hi (nlat, -kInf), fwd_lo (nfwd, kInf), fwd_hi (nfwd, -kInf);
  std::vector<unsigned char> head (nlat, 0);
  s.column.assign (nlat, 0);
  std::vector<int> column_first (nlat, scan.cw), column_last (nlat, -1);
  const float base_band = 0.1f;
  const float crown_drop = crown_drop_ + 2.f * detail::heightNoise (depth_noise_, s.zMean (), s.top - scan.offset);
  detail::forEachPartCell (scan, parts, [&] (const detail::PersonPart &part, int c, const detail::PersonGridCell &g) {
    const int bl = detail::binIndex (g.lat, s.lat_min, s.bin, nlat);
    const int bf = detail::binIndex (g.fwd, s.fwd_min, s.bin, nfwd);
    ++s.column[bl];
    const int cu = c % scan.cw;
    column_first[bl] = std::min (column_first[bl], cu);
    column_last[bl] = std::max (column_last[bl], cu);
    lat_lo[bl] = std::min (lat_lo[bl], g.h);
    lat_hi[bl] = std::max (lat_hi[bl], g.h);
    fwd_lo[bf] = std::min (fwd_lo[bf], g.h);
    fwd_hi[bf] = std::max (fwd_hi[bf], g.h);
    if (g.h >= s.top - crown_drop)
    {
      head[bl] = 1;
      // What is above the top: background, or something nearer that hides the head.
      countVerticalNeighbour (scan, part, c, -1, false, s.crown, s.crown_hidden);
    }
    // What the lowest cells stand on: the floor, the image border, a gap in the data or
    // something nearer that hides the rest; not a surface behind them.
    if (scan.with_floor && g.h <= s.bottom + base_band)
      countVerticalNeighbour (scan, part, c, 1, true, s.base, s.base_supported);
  });
  const float upright = 0.3f;
  const bool clipped = s.lat_max - s.lat_min > max_extent || s.fwd_max - s.fwd_min > max_extent;
  s.width_across = clipped ? kInf : detail::uprightExtent (lat_lo, lat_hi, s.bin, upright);
  s.width = clipped ? kInf : std::max (s.width_across, detail::uprightExtent (fwd_lo, fwd_hi, s.bin, upright));
  int run = 0, longest = 0;
  for (const auto occupied : head)
  {
    run = occupied ? run + 1 : 0;
    longest = std::max (longest, run);
  }
  s.head_width = static_cast<float> (longest) * s.bin;
  s.profile.swap (lat_hi);
  // Cells per image column of each bin: how tall the cluster is there, whatever number of
  // cell columns a bin happens to hold.
  s.fill.assign (nlat, 0.f);
  for (int b = 0; b < nlat; ++b)
    if (s.column[b] > 0)
      s.fill[b] = static_cast<float> (s.column[b]) / static_cast<float> (column_last[b] - column_first[b] + 1);
}

/** Counts the cell rows above (-1) or below (+1) cell c, unless it is of c's own cluster, in
  * seen, and in counted when it is something nearer and not connected, or outside the image,
  * or (with no_data_counts) without data: the crown hidden above, the base supported below. */
template <typename PointT> void
agex::PersonSegmentation<PointT>::countVerticalNeighbour (const detail::PersonScan &scan,
                                                          const detail::PersonPart &part, int c, int rows,
                                                          bool no_data_counts, int &seen, int &counted) const
{
  const int nv = c / scan.cw + rows;
  if (nv < 0 || nv >= scan.ch)
  {
    ++seen;
    ++counted;
    return;
  }
  const int j = c + rows * scan.cw;
  if (scan.cluster_of[j] == part.cluster)
    return;
  const detail::PersonGridCell &g = scan.grid[c], &o = scan.grid[j];
  ++seen;
  if (o.valid ? (o.z < g.z && !connected (scan, g, o, false)) : no_data_counts)
    ++counted;
}

/** The outline: neighbours outside the parts, and how many of them are background (no
  * data, the floor, or a surface farther away). Only asked for when the cheaper rules pass. */
template <typename PointT> void
agex::PersonSegmentation<PointT>::outline (const detail::PersonScan &scan, const std::vector<detail::PersonPart> &parts,
                                           detail::PersonPartStats &s) const
{
  s.outline = s.outline_background = 0;
  detail::forEachPartCell (scan, parts, [&] (const detail::PersonPart &part, int c, const detail::PersonGridCell &g) {
    detail::forEachNeighbourCell (scan, c, [&] (int j, bool diagonal) {
      if (scan.cluster_of[j] == part.cluster || detail::inPersonParts (scan, parts, j))
        return;  // inside, or the other side of a cut: not an outline
      ++s.outline;
      const detail::PersonGridCell &o = scan.grid[j];
      if (!o.valid || (o.z > g.z && !connected (scan, g, o, diagonal)))
        ++s.outline_background;
    });
  });
  s.outlined = true;
}

/** A body cut off by the image's border shows less of itself (a head and shoulders at the
  * lower border, half a body at a side): it needs only a hidden person's area. */
template <typename PointT> float
agex::PersonSegmentation<PointT>::minPersonArea (const detail::PersonPartStats &s) const
{
  return s.border ? std::min (hidden_min_area_, min_area_) : min_area_;
}

/** The rules of a person (doc/pipeline.md, "People"), cheapest first. */
template <typename PointT> agex::detail::PersonVerdict
agex::PersonSegmentation<PointT>::verdict (const detail::PersonScan &scan, const std::vector<detail::PersonPart> &parts,
                                           detail::PersonPartStats &s) const
{
  using detail::PersonVerdict;
  if (!s.cells)
    return PersonVerdict::kEmpty;
  if (s.area < minPersonArea (s))
    return PersonVerdict::kTooSmall;
  if (s.width > max_width_)
    return PersonVerdict::kTooWide;
  if (scan.with_floor)
  {
    if (s.top > max_top_)
      return PersonVerdict::kTooTall;
    if (s.top < min_top_)
      return PersonVerdict::kTooLow;
    if (s.bottom > max_bottom_ && !(s.border & PersonInfo::kBottom))
      return PersonVerdict::kFloating;
    if (s.base_supported < 0.5f * s.base)
      return PersonVerdict::kFloating;
  }
  else
  {
    if (s.top - s.bottom < fallback_min_extent_)
      return PersonVerdict::kTooFlat;
    if (s.top - s.bottom > max_top_)
      return PersonVerdict::kTooTall;
  }
  // The top narrower than the body below it; a top cut off by the image or hidden
  // behind something nearer says nothing.
  if (s.head_width > std::max (max_crown_ratio_ * s.width_across, min_crown_width_ + s.bin) &&
      !(s.border & PersonInfo::kTop) &&
      2 * s.crown_hidden < s.crown)
    return PersonVerdict::kWideTop;
  if (!s.outlined)
    outline (scan, parts, s);
  if (s.outline_background < min_background_fraction_ * s.outline)
    return PersonVerdict::kBehind;
  return PersonVerdict::kPerson;
}

/** 4-5. Person-like parts of each cluster, cut where it holds several people; the rest are
  * kept as leftovers, pieces that may yet join someone. */
template <typename PointT> void
agex::PersonSegmentation<PointT>::findCandidates (const detail::PersonScan &scan,
                                                  std::vector<detail::PersonCandidate> &people,
                                                  std::vector<detail::PersonCandidate> &leftovers) const
{
  using detail::PersonPart;
  using detail::PersonVerdict;
  constexpr float kInf = std::numeric_limits<float>::infinity ();
  // Pieces smaller than a quarter of a hand are not worth merging into anyone.
  const float min_cluster_area = 0.25f * hand_area_;
  const int clusters = static_cast<int> (scan.cluster_start.size ()) - 1;
  std::vector<PersonPart> stack;
  std::vector<char> stack_split;
  for (int id = 0; id < clusters; ++id)
  {
    // Clusters far smaller than anything of interest are skipped without measuring.
    const int size = scan.cluster_start[id + 1] - scan.cluster_start[id];
    const float z0 = scan.grid[scan.cluster_cells[scan.cluster_start[id]]].z;
    if (size * scan.coarse_area * z0 * z0 < min_cluster_area)
      continue;
    // A part that is cut goes back on the stack as its two sides: either may hold more people.
    stack.assign (1, PersonPart{id, -kInf, kInf});
    stack_split.assign (1, 0);
    while (!stack.empty ())
    {
      const PersonPart part = stack.back ();
      const bool was_split = stack_split.back ();
      stack.pop_back ();
      stack_split.pop_back ();
      detail::PersonCandidate candidate;
      candidate.parts.assign (1, part);
      measure (scan, candidate.parts, candidate.stats);
      candidate.verdict = verdict (scan, candidate.parts, candidate.stats);
      candidate.split = was_split;
      PersonPart left, right;
      if (splitAtHeads (scan, part, candidate.stats, left, right))
      {
        stack.push_back (left);
        stack.push_back (right);
        stack_split.push_back (1);
        stack_split.push_back (1);
        continue;
      }
      if (candidate.verdict == PersonVerdict::kPerson)
        people.push_back (std::move (candidate));
      else if (candidate.verdict != PersonVerdict::kEmpty)
        leftovers.push_back (std::move (candidate));
    }
  }
}

/** 5. Two people in one cluster: the first cut between heads, deepest valley first, that
  * leaves a person of its own on each side, and not a sliver (an arm beside the head). */
template <typename PointT> bool
agex::PersonSegmentation<PointT>::splitAtHeads (const detail::PersonScan &scan, const detail::PersonPart &part,
                                                const detail::PersonPartStats &s, detail::PersonPart &left,
                                                detail::PersonPart &right) const
{
  using detail::PersonVerdict;
  if (!(s.cells && s.area >= 2.f * min_area_))
    return false;  // too small to hold two people
  for (const auto &c : headCuts (scan, s))
  {
    const std::vector<detail::PersonPart> left_parts (1, detail::PersonPart{part.cluster, part.lo, c.at});
    const std::vector<detail::PersonPart> right_parts (1, detail::PersonPart{part.cluster, c.at, part.hi});
    detail::PersonPartStats left_stats, right_stats;
    measure (scan, left_parts, left_stats);
    measure (scan, right_parts, right_stats);
    if (verdict (scan, left_parts, left_stats) == PersonVerdict::kPerson &&
        verdict (scan, right_parts, right_stats) == PersonVerdict::kPerson &&
        left_stats.area >= 0.2 * s.area && right_stats.area >= 0.2 * s.area)
    {
      left = left_parts[0];
      right = right_parts[0];
      return true;
    }
  }
  return false;
}

/** Cuts between head peaks of the height profile (highest within half the head distance on
  * either side), as pcl::people::HeadBasedSubclustering finds heads; deepest valley first. */
template <typename PointT> std::vector<agex::detail::PersonCut>
agex::PersonSegmentation<PointT>::headCuts (const detail::PersonScan &scan, const detail::PersonPartStats &s) const
{
  constexpr float kInf = std::numeric_limits<float>::infinity ();
  const auto &profile = s.profile;
  const int nb = static_cast<int> (profile.size ());
  // At most the profile's length: a huge head distance must not overflow the int.
  const int window = clampedInt (std::ceil (0.5f * min_head_distance_ / s.bin), 1, std::max (1, nb));
  std::vector<int> peaks;
  for (int b = 0; b < nb; ++b)
  {
    if (!(profile[b] > -kInf) || (scan.with_floor && profile[b] < min_top_))
      continue;
    bool highest = true;
    for (int o = std::max (0, b - window); o <= std::min (nb - 1, b + window) && highest; ++o)
      highest = o == b || profile[o] < profile[b] || (profile[o] == profile[b] && o > b);
    if (highest)
      peaks.push_back (b);
  }
  std::vector<detail::PersonCut> cuts;
  for (std::size_t k = 0; k + 1 < peaks.size (); ++k)
  {
    const int a = peaks[k], b = peaks[k + 1];
    if (static_cast<float> (b - a) * s.bin < min_head_distance_)
      continue;
    // The valley between the heads, and the cut where the fewest cells are: between
    // two bodies the cluster narrows to what joins them (arms, shoulders); a cut
    // through one body (between a raised hand and the head) crosses the torso.
    float floor_of_valley = kInf;
    int neck = -1;
    for (int o = a + 1; o < b; ++o)
    {
      if (profile[o] > -kInf)
        floor_of_valley = std::min (floor_of_valley, profile[o]);
      if (neck < 0 || s.fill[o] < s.fill[neck])
        neck = o;
    }
    if (!(floor_of_valley < kInf))
      floor_of_valley = -kInf;
    const float depth = std::min (profile[a], profile[b]) - floor_of_valley;
    const float left_max = *std::max_element (s.fill.begin (), s.fill.begin () + neck);
    const float right_max = *std::max_element (s.fill.begin () + neck + 1, s.fill.end ());
    const float narrowing = s.fill[neck] / std::max (1.f, std::min (left_max, right_max));
    // Each head stands on a body: the column under it is at least half as tall as the
    // tallest (a raised fist's is only the forearm).
    const float fullest = std::max (left_max, right_max);
    const bool bodies = s.fill[a] >= 0.5f * fullest && s.fill[b] >= 0.5f * fullest;
    if (depth >= min_valley_depth_ && narrowing <= max_narrowing_ && bodies)
      cuts.push_back ({depth, s.lat_min + (static_cast<float> (neck) + 0.5f) * s.bin});
  }
  std::sort (cuts.begin (), cuts.end (),
             [] (const detail::PersonCut &x, const detail::PersonCut &y) { return x.depth > y.depth; });
  return cuts;
}

/** a and b together, when they are of different clusters (a cut is never undone: parts of
  * one cluster were found to be two people) and together a person. */
template <typename PointT> bool
agex::PersonSegmentation<PointT>::joinedPerson (const detail::PersonScan &scan, const detail::PersonCandidate &a,
                                                const detail::PersonCandidate &b, detail::PersonCandidate &both) const
{
  for (const auto &pa : a.parts)
    for (const auto &pb : b.parts)
      if (pa.cluster == pb.cluster)
        return false;
  both.parts = a.parts;
  both.parts.insert (both.parts.end (), b.parts.begin (), b.parts.end ());
  measure (scan, both.parts, both.stats);
  if (verdict (scan, both.parts, both.stats) != detail::PersonVerdict::kPerson)
    return false;
  both.verdict = detail::PersonVerdict::kPerson;
  both.split = a.split || b.split;
  both.pieces = a.pieces + b.pieces;
  return true;
}

/** 6. Merge, first: two person-like pieces close together on the floor (one person cut in
  * two by something in front) are one when together they are a person. */
template <typename PointT> void
agex::PersonSegmentation<PointT>::mergePersonLike (const detail::PersonScan &scan,
                                                   std::vector<detail::PersonCandidate> &people) const
{
  for (bool merged = true; merged;)
  {
    merged = false;
    for (std::size_t i = 0; i < people.size () && !merged; ++i)
      for (std::size_t j = i + 1; j < people.size () && !merged; ++j)
      {
        if (detail::groundDistance (people[i].stats, people[j].stats) >= merge_distance_)
          continue;
        detail::PersonCandidate both;
        if (!joinedPerson (scan, people[i], people[j], both))
          continue;
        people[i] = std::move (both);
        people.erase (people.begin () + j);
        merged = true;
      }
  }
}

/** 6. Merge, second: pieces that are nobody on their own, of different clusters, close
  * together on the floor and one above the other as seen from the camera, are a person when
  * together they pass the rules: one person cut apart by something in front (the upper body
  * floating above a board's edge, the legs below it too low), which mergePersonLike does not
  * join because neither piece is a person. Largest piece first; each joins one person at most. */
template <typename PointT> void
agex::PersonSegmentation<PointT>::mergeHiddenPieces (const detail::PersonScan &scan,
                                                     std::vector<detail::PersonCandidate> &people,
                                                     std::vector<detail::PersonCandidate> &leftovers) const
{
  using detail::PersonVerdict;
  if (!scan.with_floor)
    return;  // the floor-free rule has no heights to tell a cut-off piece by
  auto mergeable = [&] (const detail::PersonCandidate &c) {
    return c.stats.cells > 0 && c.stats.area >= 0.25f * min_area_ &&
           (c.verdict == PersonVerdict::kTooSmall || c.verdict == PersonVerdict::kTooLow ||
            c.verdict == PersonVerdict::kFloating);
  };
  std::sort (leftovers.begin (), leftovers.end (), [] (const detail::PersonCandidate &a,
                                                       const detail::PersonCandidate &b) {
    return a.stats.area > b.stats.area;
  });
  std::vector<unsigned char> used (leftovers.size (), 0);
  for (std::size_t i = 0; i < leftovers.size (); ++i)
  {
    if (used[i] || !mergeable (leftovers[i]))
      continue;
    for (std::size_t j = i + 1; j < leftovers.size (); ++j)
    {
      const detail::PersonPartStats &p = leftovers[i].stats, &q = leftovers[j].stats;
      if (used[j] || !mergeable (leftovers[j]) || detail::groundDistance (p, q) >= merge_distance_)
        continue;
      const float overlap = std::min (p.az_max, q.az_max) - std::max (p.az_min, q.az_min);
      if (overlap < 0.5f * std::min (p.az_max - p.az_min, q.az_max - q.az_min))
        continue;
      detail::PersonCandidate both;
      if (!joinedPerson (scan, leftovers[i], leftovers[j], both))
        continue;
      people.push_back (std::move (both));
      used[i] = used[j] = 1;
      break;
    }
  }
  detail::dropUsed (leftovers, used);
}

/** 6. Merge, then: small pieces, largest first, join the nearest person they touch in the
  * image (a hand held out in front of the arm) or lie in front of or behind (overlapping
  * directions from the camera: a leg seen below a chair). Decisions use each person's own
  * statistics; a piece once merged lets the next ones touch it. Leaves the person of each
  * cell in scan.cell_person. */
template <typename PointT> void
agex::PersonSegmentation<PointT>::mergePieces (detail::PersonScan &scan, std::vector<detail::PersonCandidate> &people,
                                               std::vector<detail::PersonCandidate> &leftovers) const
{
  std::sort (leftovers.begin (), leftovers.end (), [] (const detail::PersonCandidate &a,
                                                       const detail::PersonCandidate &b) {
    return a.stats.area > b.stats.area;
  });
  scan.cell_person.assign (scan.grid.size (), -1);
  for (int k = 0; k < static_cast<int> (people.size ()); ++k)
    detail::claimPersonCells (scan, people[k].parts, k);
  std::vector<detail::PersonPartStats> own (people.size ());
  for (std::size_t k = 0; k < people.size (); ++k)
    own[k] = people[k].stats;
  std::vector<unsigned char> touches (people.size ());
  bool any_merged = false;
  std::vector<unsigned char> merged_into (people.size (), 0);
  std::vector<unsigned char> used (leftovers.size (), 0);  // the pieces no one took stay leftovers
  for (std::size_t i = 0; i < leftovers.size (); ++i)
  {
    const detail::PersonCandidate &piece = leftovers[i];
    if (piece.verdict == detail::PersonVerdict::kTooTall || piece.stats.width > 0.5f * max_width_)
      continue;  // walls, shelves, desks
    detail::touchedPersons (scan, piece.parts, touches);
    const int best = nearestPerson (own, piece.stats, touches);
    if (best < 0)
      continue;
    detail::PersonCandidate &person = people[best];
    person.parts.insert (person.parts.end (), piece.parts.begin (), piece.parts.end ());
    person.pieces += piece.pieces;
    detail::claimPersonCells (scan, piece.parts, best);
    merged_into[best] = 1;
    any_merged = true;
    used[i] = 1;
  }
  detail::dropUsed (leftovers, used);
  if (any_merged)
    for (std::size_t k = 0; k < people.size (); ++k)
      if (merged_into[k])
      {
        measure (scan, people[k].parts, people[k].stats);
        people[k].stats.top = std::max (own[k].top, people[k].stats.top);
      }
}

/** The person a small piece joins: the nearest on the floor within reach that it touches or
  * lies in front of or behind, and that it does not reach above; -1: none. */
template <typename PointT> int
agex::PersonSegmentation<PointT>::nearestPerson (const std::vector<detail::PersonPartStats> &own,
                                                 const detail::PersonPartStats &p,
                                                 const std::vector<unsigned char> &touches) const
{
  int best = -1;
  float best_distance = merge_reach_;
  for (int k = 0; k < static_cast<int> (own.size ()); ++k)
  {
    const detail::PersonPartStats &q = own[k];
    // Not above the person's top, unless that top is hidden behind something nearer.
    const bool hidden_top = 2 * q.crown_hidden >= q.crown && q.crown > 0;
    if (p.area > 0.5 * q.area || p.top > (hidden_top ? q.bottom + max_top_ : q.top + 0.1f))
      continue;
    const float overlap = std::min (p.az_max, q.az_max) - std::max (p.az_min, q.az_min);
    if (!touches[k] && overlap < 0.5f * (p.az_max - p.az_min))
      continue;
    const float distance = detail::groundDistance (p, q);
    if (distance <= best_distance)
    {
      best = k;
      best_distance = distance;
    }
  }
  return best;
}

/** 6. Hidden persons: pieces left over that are nobody alone and lie behind a person they
  * touch in the image are a person seen round that nearer one (doc/pipeline.md, "People").
  * Largest piece first; a piece joins the first hidden person within the merge reach of it
  * on the floor. Claims the kept ones' cells in scan.cell_person. */
template <typename PointT> void
agex::PersonSegmentation<PointT>::findHiddenPersons (detail::PersonScan &scan,
                                                     std::vector<detail::PersonCandidate> &people,
                                                     const std::vector<detail::PersonCandidate> &leftovers) const
{
  using detail::PersonVerdict;
  if (!find_hidden_ || !scan.with_floor || people.empty ())
    return;  // without a floor no heights tell a fragment of a body from anything else
  const std::size_t seen = people.size ();
  std::vector<unsigned char> touches (seen);
  std::vector<detail::PersonCandidate> hidden;
  for (const auto &piece : leftovers)  // largest first (mergePieces)
  {
    const detail::PersonPartStats &p = piece.stats;
    const bool part_of_a_body = piece.verdict == PersonVerdict::kTooSmall || piece.verdict == PersonVerdict::kTooLow ||
                                piece.verdict == PersonVerdict::kFloating;
    if (!part_of_a_body || !p.cells || p.width > 0.5f * max_width_ || p.top > max_top_)
      continue;
    detail::touchedPersons (scan, piece.parts, touches);
    bool behind = false;
    for (std::size_t k = 0; k < seen && !behind; ++k)
      behind = touches[k] && people[k].stats.zMean () + merge_distance_ < p.zMean ();
    if (!behind)
      continue;
    auto joins = std::find_if (hidden.begin (), hidden.end (), [&] (const detail::PersonCandidate &h) {
      return detail::groundDistance (h.stats, p) <= merge_reach_;
    });
    if (joins == hidden.end ())
    {
      hidden.push_back (piece);
      hidden.back ().hidden = true;
      continue;
    }
    joins->parts.insert (joins->parts.end (), piece.parts.begin (), piece.parts.end ());
    joins->pieces += piece.pieces;
    measure (scan, joins->parts, joins->stats);
  }
  // What is kept: enough of a body, something of it as high as a person's top, and the
  // background rule of whole persons (a panel seen between two people, hemmed in by them,
  // is no one).
  for (auto &h : hidden)
  {
    if (h.stats.area < hidden_min_area_ || h.stats.top < min_top_ || h.stats.width > max_width_)
      continue;
    outline (scan, h.parts, h.stats);
    if (h.stats.outline_background < min_background_fraction_ * h.stats.outline)
      continue;
    detail::claimPersonCells (scan, h.parts, static_cast<int> (people.size ()));
    people.push_back (std::move (h));
  }
}

/** 8. Full resolution. A pixel in the block of one of the person's cells, or of a free
  * cell next to them, belongs to the person when its depth lies within the gap of the
  * depths of the person's cells around it: a test per pixel, so that what costs the
  * most at full resolution (following connections pixel by pixel) is left to the mesh
  * segmentation that runs on the persons' pixels anyway. */
template <typename PointT> void
agex::PersonSegmentation<PointT>::takePixels (const detail::PersonScan &scan,
                                              const std::vector<detail::PersonCandidate> &people,
                                              pcl::PointCloud<pcl::Label> &labels,
                                              std::vector<detail::PersonPixels> &pixels) const
{
  detail::PersonBlocks blocks;
  blocks.stamp.assign (scan.grid.size (), -1);
  blocks.zlo.resize (scan.grid.size ());
  blocks.zhi.resize (scan.grid.size ());
  pixels.assign (people.size (), detail::PersonPixels ());
  for (int k = 0; k < static_cast<int> (people.size ()); ++k)
  {
    const bool bounded = detail::personBlocks (scan, people[k].parts, k, blocks);
    // The floor where the person stands, from the floor cells among its blocks (the plane
    // was fitted to the whole floor, and may be a centimetre or two off here): pixels of
    // the feet above it by more than the height noise are the person's (doc/pipeline.md).
    blocks.floor_level = 0.f;
    blocks.levels.clear ();
    if (scan.with_floor)
      for (const int c : blocks.cells)
      {
        const detail::PersonGridCell &g = scan.grid[c];
        if (g.pixel >= 0 && !g.valid && std::abs (g.h) < floorMargin (scan, g.z, g.h))
          blocks.levels.push_back (g.h);
      }
    if (blocks.levels.size () >= 3)
    {
      const auto middle = blocks.levels.begin () + blocks.levels.size () / 2;
      std::nth_element (blocks.levels.begin (), middle, blocks.levels.end ());
      blocks.floor_level = *middle;
    }
    personPixels (scan, people[k].parts, k, bounded, blocks, labels, pixels[k]);
  }
}

/** Person k's pixels, block row by block row so that the indices come out sorted; a pixel
  * taken by an earlier person stays theirs. */
template <typename PointT> void
agex::PersonSegmentation<PointT>::personPixels (const detail::PersonScan &scan,
                                                const std::vector<detail::PersonPart> &parts, int k, bool bounded,
                                                const detail::PersonBlocks &blocks,
                                                pcl::PointCloud<pcl::Label> &labels, detail::PersonPixels &out) const
{
  const PointCloud &cloud = *input_;
  const int width = scan.width, height = scan.height, step = scan.step, cw = scan.cw;
  const std::vector<int> &candidates = blocks.cells;
  const auto label = static_cast<std::uint32_t> (k);
  auto &indices = out.indices;
  indices.reserve (candidates.size () * step * step);
  Eigen::Vector3d &sum = out.sum;
  for (std::size_t row_start = 0; row_start < candidates.size ();)
  {
    const int cv = candidates[row_start] / cw;
    std::size_t row_end = row_start;
    while (row_end < candidates.size () && candidates[row_end] / cw == cv)
      ++row_end;
    const int v0 = cv * step, v1 = std::min (height, v0 + step);
    for (int v = v0; v < v1; ++v)
      for (std::size_t q = row_start; q < row_end; ++q)
      {
        const int c = candidates[q];
        const int u0 = (c % cw) * step, u1 = std::min (width, u0 + step);
        // Pixels of a block are up to a cell apart from the cells' points.
        const float lo = blocks.zlo[c] -
                         detail::personDepthGap (blocks.zlo[c], scan.coarse_spacing, max_slope_, depth_noise_, min_gap_);
        const float hi = blocks.zhi[c] +
                         detail::personDepthGap (blocks.zhi[c], scan.coarse_spacing, max_slope_, depth_noise_, min_gap_);
        Eigen::Vector3f block_sum = Eigen::Vector3f::Zero ();
        for (int u = u0; u < u1; ++u)
        {
          const int i = v * width + u;
          const PointT &p = cloud[i];
          // The depth test first: it also rejects a NaN depth; x + y is finite only if both are.
          if (!(p.z >= lo && p.z <= hi) || labels[i].label != kUnlabelled || !std::isfinite (p.x + p.y) ||
              !(fake_indices_ || scan.selected[i]) || !(p.z > 0.f))
            continue;
          if (scan.with_floor)
          {
            // Below the floor margin only the feet: points above the floor under this
            // person by more than three times their height noise (and a centimetre),
            // right under a pixel of the person (the shoe goes on down from the leg; a
            // noisy bit of the floor beside it does not).
            const float h = scan.normal.dot (p.getVector3fMap ()) + scan.offset;
            if (h < floorMargin (scan, p.z, h) &&
                (!floor_contact_ || h - blocks.floor_level < std::max (kMinFootHeight,
                                                    3.f * detail::heightNoise (depth_noise_, p.z, h - scan.offset)) ||
                 !detail::belowPerson (labels, i, width, label)))
              continue;
          }
          if (bounded)
          {
            const float lat = scan.lateral.dot (p.getVector3fMap ());
            bool inside = false;
            for (const auto &part : parts)
              inside = inside || (lat >= part.lo && lat < part.hi);
            if (!inside)
              continue;
          }
          labels[i].label = label;
          indices.push_back (i);
          block_sum += p.getVector3fMap ();
        }
        sum += block_sum.cast<double> ();
      }
    row_start = row_end;
  }
  out.count = static_cast<int> (indices.size ());
}

/** The persons in the documented order, largest first (ties: lowest first index); the
  * labels are renumbered to follow it. */
template <typename PointT> void
agex::PersonSegmentation<PointT>::describePersons (const detail::PersonScan &scan,
                                                   const std::vector<detail::PersonCandidate> &people,
                                                   std::vector<detail::PersonPixels> &pixels,
                                                   pcl::PointCloud<pcl::Label> &labels,
                                                   std::vector<pcl::PointIndices> &persons)
{
  std::vector<int> order;
  for (int k = 0; k < static_cast<int> (people.size ()); ++k)
    if (pixels[k].count > 0)
      order.push_back (k);
  std::sort (order.begin (), order.end (), [&] (int a, int b) {
    return pixels[a].count != pixels[b].count ? pixels[a].count > pixels[b].count
                                              : pixels[a].indices.front () < pixels[b].indices.front ();
  });
  persons.resize (order.size ());
  for (std::size_t r = 0; r < order.size (); ++r)
  {
    const int k = order[r];
    persons[r].header = input_->header;
    persons[r].indices.swap (pixels[k].indices);
    for (const auto i : persons[r].indices)
      labels[i].label = static_cast<std::uint32_t> (r);
    infos_.push_back (personInfo (scan, people[k], k, pixels[k]));
  }
}

/** What is known about person k (PersonInfo); its hand pixels decide "too far". */
template <typename PointT> agex::PersonInfo
agex::PersonSegmentation<PointT>::personInfo (const detail::PersonScan &scan, const detail::PersonCandidate &person,
                                              int k, const detail::PersonPixels &pixels) const
{
  const detail::PersonPartStats &s = person.stats;
  PersonInfo info;
  info.points = pixels.count;
  info.centroid = (pixels.sum / static_cast<double> (pixels.count)).cast<float> ();
  info.ground = scan.with_floor
                    ? Eigen::Vector3f (info.centroid - (scan.normal.dot (info.centroid) + scan.offset) * scan.normal)
                    : info.centroid;
  std::vector<float> depths;
  for (const auto &part : person.parts)
    for (int q = scan.cluster_start[part.cluster]; q < scan.cluster_start[part.cluster + 1]; ++q)
      if (scan.cell_person[scan.cluster_cells[q]] == k)
        depths.push_back (scan.grid[scan.cluster_cells[q]].z);
  std::nth_element (depths.begin (), depths.begin () + depths.size () / 2, depths.end ());
  info.distance = depths[depths.size () / 2];
  info.top = s.top;
  info.bottom = s.bottom;
  info.width = s.width;
  info.area = static_cast<float> (s.area);
  info.hand_pixels = hand_area_ * scan.fx * scan.fy / (info.distance * info.distance);
  info.too_far = info.hand_pixels < min_hand_pixels_;
  info.on_floor = scan.with_floor;
  info.split = person.split;
  info.pieces = person.pieces;
  info.hidden = person.hidden;
  info.border = s.border;
  return info;
}

#define PCL_INSTANTIATE_PersonSegmentation(T) template class PCL_EXPORTS agex::PersonSegmentation<T>;
