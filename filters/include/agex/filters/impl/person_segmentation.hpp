#pragma once

#include <agex/common/organized_neighbourhood.h>
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

inline float
personDepthGap (float z, float spacing_per_metre, float slope, float noise, float min_gap)
{
  return std::max (min_gap, slope * spacing_per_metre * z + 3.f * noise * z * z);
}

/** How far the floor's inliers spread on it: the smaller standard deviation of their
  * positions in the plane (a strip, such as a body's lower edge cut by the image, has
  * almost none). */
template <typename PointT> float
floorSpread (const pcl::PointCloud<PointT> &cloud, const pcl::Indices &indices, const Eigen::Vector4f &plane,
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
  int count = 0;
  for (const auto i : indices)
  {
    const Eigen::Vector3f p = cloud[i].getVector3fMap ();
    if (std::abs (normal.dot (p) + plane[3]) >= distance)
      continue;
    const Eigen::Vector2d q (a.dot (p), b.dot (p));
    sum += q;
    products += q * q.transpose ();
    ++count;
  }
  if (count < 3)
    return 0.f;
  const Eigen::Vector2d mean = sum / count;
  const Eigen::Matrix2d covariance = products / count - mean * mean.transpose ();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver (covariance, Eigen::EigenvaluesOnly);
  return static_cast<float> (std::sqrt (std::max (0.0, solver.eigenvalues ()[0])));
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
         positive (min_head_distance_) && positive (min_valley_depth_) && max_narrowing_ > 0.f &&
         max_narrowing_ <= 1.f && non_negative (merge_reach_) &&
         non_negative (merge_distance_) && non_negative (fallback_min_extent_) && min_background_fraction_ >= 0.f &&
         min_background_fraction_ <= 1.f && positive (hand_area_) && non_negative (min_hand_pixels_);
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

template <typename PointT> void
agex::PersonSegmentation<PointT>::segment (pcl::PointCloud<pcl::Label> &labels, std::vector<pcl::PointIndices> &persons)
{
  using detail::PersonGridCell;
  using detail::PersonPart;
  using detail::PersonPartStats;
  using detail::PersonVerdict;
  constexpr float kInf = std::numeric_limits<float>::infinity ();

  persons.clear ();
  labels.clear ();
  infos_.clear ();
  floor_found_ = false;
  floor_plane_.setZero ();
  used_fx_ = used_fy_ = 0.f;
  used_step_ = 0;
  if (!initCompute ())
    return;
  if (!input_->isOrganized ())
  {
    PCL_ERROR ("[agex::%s::segment] The input cloud is not organized (height %u); persons are found on the "
               "pixel grid.\n", getClassName ().c_str (), input_->height);
    deinitCompute ();
    return;
  }
  if (!validParameters ())
  {
    PCL_ERROR ("[agex::%s::segment] Invalid parameters: every length, area and count must be finite and "
               "non-negative (floor distance, minimum gap, crown, split and hand limits, maximum top and width "
               "positive), the minimum top below the maximum, the floor tilt under 90 degrees, the coarse step "
               "0-64, the narrowing in (0, 1], the background fraction in [0, 1] and the up axis non-zero.\n",
               getClassName ().c_str ());
    deinitCompute ();
    return;
  }
  if (floor_given_ && !(given_floor_.allFinite () && given_floor_.head<3> ().norm () > 0.f))
  {
    PCL_ERROR ("[agex::%s::segment] The floor plane (%g, %g, %g, %g) has no finite, non-zero normal.\n",
               getClassName ().c_str (), given_floor_[0], given_floor_[1], given_floor_[2], given_floor_[3]);
    deinitCompute ();
    return;
  }

  const PointCloud &cloud = *input_;
  const int width = static_cast<int> (cloud.width), height = static_cast<int> (cloud.height);
  const int n = static_cast<int> (cloud.size ());
  labels.width = cloud.width;
  labels.height = cloud.height;
  labels.is_dense = cloud.is_dense;
  labels.header = cloud.header;
  pcl::Label nobody;
  nobody.label = kUnlabelled;
  labels.points.assign (n, nobody);

  std::vector<unsigned char> selected;
  if (!fake_indices_)
  {
    selected.assign (n, 0);
    for (const auto i : *indices_)
      if (i >= 0 && i < n)
        selected[i] = 1;
  }
  auto usable = [&] (int i) {
    const PointT &p = cloud[i];
    return (fake_indices_ || selected[i]) && std::isfinite (p.x) && std::isfinite (p.y) && std::isfinite (p.z) &&
           p.z > 0.f;
  };

  // Focal lengths: u = fx x / z + cx, fitted by least squares on a lattice of pixels.
  float fx = fx_, fy = fy_;
  if (!(fx > 0.f) || !(fy > 0.f))
  {
    const int stride = std::max (1, static_cast<int> (std::lround (std::sqrt (n / 4800.0))));
    double m = 0, su = 0, sa = 0, saa = 0, sua = 0, sv = 0, sb = 0, sbb = 0, svb = 0;
    for (int v = stride / 2; v < height; v += stride)
      for (int u = stride / 2; u < width; u += stride)
      {
        const int i = v * width + u;
        if (!usable (i))
          continue;
        const PointT &p = cloud[i];
        const double a = p.x / p.z, b = p.y / p.z;
        m += 1, su += u, sa += a, saa += a * a, sua += u * a;
        sv += v, sb += b, sbb += b * b, svb += v * b;
      }
    const double var_a = m > 0 ? saa - sa * sa / m : 0.0, var_b = m > 0 ? sbb - sb * sb / m : 0.0;
    const double efx = var_a > 1e-12 ? (sua - su * sa / m) / var_a : 0.0;
    const double efy = var_b > 1e-12 ? (svb - sv * sb / m) / var_b : 0.0;
    // Too few or degenerate points: the Kinect's 525 px at 640 columns, scaled.
    const double fallback = 525.0 * width / 640.0;
    if (!(fx > 0.f))
      fx = static_cast<float> (m >= 16 && std::isfinite (efx) && efx > 1.0 ? efx : fallback);
    if (!(fy > 0.f))
      fy = static_cast<float> (m >= 16 && std::isfinite (efy) && efy > 1.0 ? efy : fallback);
  }
  used_fx_ = fx;
  used_fy_ = fy;

  // 1. The coarse grid: the block's centre pixel, or else the first usable centre of its
  // quarters (a block without either is empty: its pixels may still join a neighbour's
  // person at full resolution).
  const int step = coarse_step_ > 0 ? coarse_step_
                                    : std::max (1, static_cast<int> (std::lround (kAutoCellAngle * std::min (fx, fy))));
  used_step_ = step;
  const int cw = (width + step - 1) / step, ch = (height + step - 1) / step;
  std::vector<PersonGridCell> grid (static_cast<std::size_t> (cw) * ch);
  pcl::IndicesPtr cell_pixels (new pcl::Indices);
  for (int cv = 0; cv < ch; ++cv)
    for (int cu = 0; cu < cw; ++cu)
    {
      const int u0 = cu * step, v0 = cv * step;
      const int u1 = std::min (width, u0 + step), v1 = std::min (height, v0 + step);
      const int bu = u1 - u0, bv = v1 - v0;
      int pixel = (v0 + bv / 2) * width + u0 + bu / 2;
      if (!usable (pixel))
      {
        pixel = -1;
        for (int q = 0; q < 4 && pixel < 0; ++q)
        {
          const int candidate = (v0 + (q / 2 * 2 + 1) * bv / 4) * width + u0 + (q % 2 * 2 + 1) * bu / 4;
          if (usable (candidate))
            pixel = candidate;
        }
      }
      grid[cv * cw + cu].pixel = pixel;
      if (pixel >= 0)
        cell_pixels->push_back (pixel);
    }
  if (cell_pixels->empty ())
  {
    deinitCompute ();
    return;
  }
  const float per_pixel = 1.f / std::min (fx, fy);  // spacing of adjacent pixels per metre of depth

  // 2. The floor: given, or searched for among the cells.
  Eigen::Vector3f normal;
  float offset = 0.f;
  if (floor_given_)
  {
    floor_plane_ = given_floor_ / given_floor_.head<3> ().norm ();
    if (floor_plane_.head<3> ().dot (up_) < 0.f)
      floor_plane_ = -floor_plane_;  // heights grow upwards whichever way the plane was written
    floor_found_ = true;
  }
  else
  {
    // RANSAC looks only at cells whose surface (from the cells to the right and below)
    // faces up within the tilt limit and 20 degrees more: the floor is most of them, so
    // RANSAC needs a few dozen draws instead of a thousand.
    pcl::IndicesPtr level (new pcl::Indices);
    const Eigen::Vector3f up = up_.normalized ();
    const float min_cos = std::cos (std::min (89.f, floor_max_tilt_deg_ + 20.f) * static_cast<float> (M_PI) / 180.f);
    const float spacing = step / std::min (fx, fy);
    for (int cv = 0; cv + 1 < ch; ++cv)
      for (int cu = 0; cu + 1 < cw; ++cu)
      {
        const int c = cv * cw + cu;
        const int r = grid[c].pixel, d = grid[c + cw].pixel, q = grid[c + 1].pixel;
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
    agex::FloorRemoval<PointT> floor;
    floor.setInputCloud (input_);
    floor.setIndices (level);
    floor.setUpAxis (up_);
    floor.setMaxTilt (floor_max_tilt_deg_);
    floor.setDistanceThreshold (floor_distance_);
    // About 2,000 points: plenty for a plane, and RANSAC's cost grows with them.
    floor.setSampleStride (std::max (1, static_cast<int> (level->size () / 2000)));
    pcl::Indices above;
    floor.filter (above);
    floor_found_ = floor.getFloorFound () && detail::floorSpread (cloud, *cell_pixels, floor.getFloorPlane (),
                                                                   floor_distance_) >= min_floor_spread_;
    if (floor_found_)
      floor_plane_ = floor.getFloorPlane ();
  }
  const bool with_floor = floor_found_;
  if (with_floor)
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
  const float noise = depth_noise_;
  auto floorMargin = [&] (float z) { return std::max (floor_distance_, 3.f * noise * z * z); };
  auto heightOf = [&] (const PointT &p) { return normal.dot (p.getVector3fMap ()) + offset; };

  for (auto &cell : grid)
  {
    if (cell.pixel < 0)
      continue;
    const PointT &p = cloud[cell.pixel];
    const Eigen::Vector3f xyz = p.getVector3fMap ();
    cell.z = p.z;
    cell.h = normal.dot (xyz) + offset;
    cell.lat = lateral.dot (xyz);
    cell.fwd = forward.dot (xyz);
    cell.valid = !with_floor || cell.h >= floorMargin (p.z);
  }

  // 3. Clusters of connected cells.
  const float coarse_spacing = step * per_pixel;
  auto connected = [&] (const PersonGridCell &a, const PersonGridCell &b, bool diagonal) {
    const float zm = 0.5f * (a.z + b.z);
    const float spacing = diagonal ? coarse_spacing * 1.41421356f : coarse_spacing;
    return std::abs (a.z - b.z) <= detail::personDepthGap (zm, spacing, max_slope_, noise, min_gap_);
  };
  std::vector<int> cluster_of (grid.size (), -1);
  std::vector<int> cluster_start (1, 0), cluster_cells;
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
      const int cu = c % cw, cv = c / cw;
      for (const auto &d : kAllNeighbours)
      {
        const int nu = cu + d[0], nv = cv + d[1];
        if (nu < 0 || nu >= cw || nv < 0 || nv >= ch)
          continue;
        const int j = nv * cw + nu;
        if (!grid[j].valid || cluster_of[j] >= 0 || !connected (grid[c], grid[j], d[0] != 0 && d[1] != 0))
          continue;
        cluster_of[j] = id;
        cluster_cells.push_back (j);
      }
    }
    cluster_start.push_back (static_cast<int> (cluster_cells.size ()));
  }
  const int clusters = static_cast<int> (cluster_start.size ()) - 1;

  auto inPart = [&] (const PersonPart &part, int c) {
    return cluster_of[c] == part.cluster && grid[c].lat >= part.lo && grid[c].lat < part.hi;
  };
  auto inParts = [&] (const std::vector<PersonPart> &parts, int c) {
    for (const auto &part : parts)
      if (inPart (part, c))
        return true;
    return false;
  };

  // Statistics of a set of parts (one person, or a candidate).
  const float coarse_area = coarse_spacing * coarse_spacing;
  auto measure = [&] (const std::vector<PersonPart> &parts, PersonPartStats &s) {
    s = PersonPartStats ();
    for (const auto &part : parts)
      for (int k = cluster_start[part.cluster]; k < cluster_start[part.cluster + 1]; ++k)
      {
        const int c = cluster_cells[k];
        const PersonGridCell &g = grid[c];
        if (g.lat < part.lo || g.lat >= part.hi)
          continue;
        ++s.cells;
        s.area += coarse_area * g.z * g.z;
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
        const int cu = c % cw, cv = c / cw;
        s.border |= (cu == 0 ? PersonInfo::kLeft : 0u) | (cu == cw - 1 ? PersonInfo::kRight : 0u) |
                    (cv == 0 ? PersonInfo::kTop : 0u) | (cv == ch - 1 ? PersonInfo::kBottom : 0u);
      }
    if (!s.cells)
      return;
    if (s.area < min_area_)
    {
      // Too small for anyone (a possible piece of someone): the bins are not needed.
      s.width = s.width_across = std::max (s.lat_max - s.lat_min, s.fwd_max - s.fwd_min);
      return;
    }
    // Bins across (lat) and along (fwd) the view: upright extent and the crown, the cells
    // within the crown drop (plus twice the noise) of the top.
    s.bin = std::max (0.05f, 1.5f * coarse_spacing * s.zMean ());
    const float max_extent = 8.f;
    auto bins = [&] (float lo, float hi) {
      return static_cast<int> (std::min (max_extent, hi - lo) / s.bin) + 1;
    };
    const int nlat = bins (s.lat_min, s.lat_max), nfwd = bins (s.fwd_min, s.fwd_max);
    std::vector<float> lat_lo (nlat, kInf), lat_hi (nlat, -kInf), fwd_lo (nfwd, kInf), fwd_hi (nfwd, -kInf);
    std::vector<unsigned char> head (nlat, 0);
    s.column.assign (nlat, 0);
    std::vector<int> column_first (nlat, cw), column_last (nlat, -1);
    const float base_band = 0.1f;
    const float crown_drop = crown_drop_ + 2.f * noise * s.zMean () * s.zMean ();
    for (const auto &part : parts)
      for (int k = cluster_start[part.cluster]; k < cluster_start[part.cluster + 1]; ++k)
      {
        const PersonGridCell &g = grid[cluster_cells[k]];
        if (g.lat < part.lo || g.lat >= part.hi)
          continue;
        const int bl = std::min (nlat - 1, static_cast<int> ((g.lat - s.lat_min) / s.bin));
        const int bf = std::min (nfwd - 1, static_cast<int> ((g.fwd - s.fwd_min) / s.bin));
        ++s.column[bl];
        const int cu = cluster_cells[k] % cw;
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
          const int c = cluster_cells[k];
          const int j = c - cw;
          if (j < 0)
          {
            ++s.crown;
            ++s.crown_hidden;
          }
          else if (cluster_of[j] != part.cluster)
          {
            const PersonGridCell &o = grid[j];
            ++s.crown;
            if (o.valid && o.z < g.z && !connected (g, o, false))
              ++s.crown_hidden;
          }
        }
        if (with_floor && g.h <= s.bottom + base_band)
        {
          // What the lowest cells stand on: the floor, the image border, a gap in the
          // data or something nearer that hides the rest; not a surface behind them.
          const int c = cluster_cells[k];
          if (c / cw + 1 >= ch)
          {
            ++s.base;
            ++s.base_supported;
            continue;
          }
          const int j = c + cw;
          if (cluster_of[j] == part.cluster)
            continue;
          const PersonGridCell &o = grid[j];
          ++s.base;
          if (!o.valid || (o.z < g.z && !connected (g, o, false)))
            ++s.base_supported;
        }
      }
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
  };

  // The outline: neighbours outside the parts, and how many of them are background (no
  // data, the floor, or a surface farther away). Only asked for when the cheaper rules pass.
  auto outline = [&] (const std::vector<PersonPart> &parts, PersonPartStats &s) {
    s.outline = s.outline_background = 0;
    for (const auto &part : parts)
      for (int k = cluster_start[part.cluster]; k < cluster_start[part.cluster + 1]; ++k)
      {
        const int c = cluster_cells[k];
        const PersonGridCell &g = grid[c];
        if (g.lat < part.lo || g.lat >= part.hi)
          continue;
        const int cu = c % cw, cv = c / cw;
        for (const auto &d : kAllNeighbours)
        {
          const int nu = cu + d[0], nv = cv + d[1];
          if (nu < 0 || nu >= cw || nv < 0 || nv >= ch)
            continue;
          const int j = nv * cw + nu;
          if (cluster_of[j] == part.cluster || inParts (parts, j))
            continue;  // inside, or the other side of a cut: not an outline
          ++s.outline;
          const PersonGridCell &o = grid[j];
          if (!o.valid || (o.z > g.z && !connected (g, o, d[0] != 0 && d[1] != 0)))
            ++s.outline_background;
        }
      }
    s.outlined = true;
  };

  auto verdict = [&] (const std::vector<PersonPart> &parts, PersonPartStats &s) {
    if (!s.cells)
      return PersonVerdict::kEmpty;
    if (s.area < min_area_)
      return PersonVerdict::kTooSmall;
    if (s.width > max_width_)
      return PersonVerdict::kTooWide;
    if (with_floor)
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
    if (s.head_width > max_crown_ratio_ * s.width_across && !(s.border & PersonInfo::kTop) &&
        2 * s.crown_hidden < s.crown)
      return PersonVerdict::kWideTop;
    if (!s.outlined)
      outline (parts, s);
    if (s.outline_background < min_background_fraction_ * s.outline)
      return PersonVerdict::kBehind;
    return PersonVerdict::kPerson;
  };

  // 4-5. Person-like parts of each cluster, cut where it holds several people.
  struct Candidate
  {
    std::vector<PersonPart> parts;
    PersonPartStats stats;
    PersonVerdict verdict = PersonVerdict::kEmpty;
    bool split = false;
    int pieces = 1;
  };
  std::vector<Candidate> people, leftovers;
  // Pieces smaller than a quarter of a hand are not worth merging into anyone.
  const float min_cluster_area = 0.25f * hand_area_;
  std::vector<PersonPart> stack;
  std::vector<char> stack_split;
  for (int id = 0; id < clusters; ++id)
  {
    // Clusters far smaller than anything of interest are skipped without measuring.
    const int size = cluster_start[id + 1] - cluster_start[id];
    const float z0 = grid[cluster_cells[cluster_start[id]]].z;
    if (size * coarse_area * z0 * z0 < min_cluster_area)
      continue;
    stack.assign (1, PersonPart{id, -kInf, kInf});
    stack_split.assign (1, 0);
    while (!stack.empty ())
    {
      const PersonPart part = stack.back ();
      const bool was_split = stack_split.back ();
      stack.pop_back ();
      stack_split.pop_back ();
      Candidate candidate;
      candidate.parts.assign (1, part);
      measure (candidate.parts, candidate.stats);
      const PersonPartStats &s = candidate.stats;
      candidate.verdict = verdict (candidate.parts, candidate.stats);
      candidate.split = was_split;

      // Head peaks: highest within half the head distance on either side.
      bool cut = false;
      if (s.cells && s.area >= 2.f * min_area_)
      {
        const auto &profile = s.profile;
        const int nb = static_cast<int> (profile.size ());
        const int window = std::max (1, static_cast<int> (std::ceil (0.5f * min_head_distance_ / s.bin)));
        std::vector<int> peaks;
        for (int b = 0; b < nb; ++b)
        {
          if (!(profile[b] > -kInf) || (with_floor && profile[b] < min_top_))
            continue;
          bool highest = true;
          for (int o = std::max (0, b - window); o <= std::min (nb - 1, b + window) && highest; ++o)
            highest = o == b || profile[o] < profile[b] || (profile[o] == profile[b] && o > b);
          if (highest)
            peaks.push_back (b);
        }
        struct Cut
        {
          float depth, at;
        };
        std::vector<Cut> cuts;
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
        std::sort (cuts.begin (), cuts.end (), [] (const Cut &x, const Cut &y) { return x.depth > y.depth; });
        for (const auto &c : cuts)
        {
          Candidate left, right;
          left.parts.assign (1, PersonPart{id, part.lo, c.at});
          right.parts.assign (1, PersonPart{id, c.at, part.hi});
          measure (left.parts, left.stats);
          measure (right.parts, right.stats);
          // Each side a person of its own, and not a sliver (an arm beside the head).
          if (verdict (left.parts, left.stats) == PersonVerdict::kPerson &&
              verdict (right.parts, right.stats) == PersonVerdict::kPerson &&
              left.stats.area >= 0.2 * s.area && right.stats.area >= 0.2 * s.area)
          {
            stack.push_back (left.parts[0]);
            stack.push_back (right.parts[0]);
            stack_split.push_back (1);
            stack_split.push_back (1);
            cut = true;
            break;
          }
        }
      }
      if (cut)
        continue;
      if (candidate.verdict == PersonVerdict::kPerson)
        people.push_back (std::move (candidate));
      else if (candidate.verdict != PersonVerdict::kEmpty)
        leftovers.push_back (std::move (candidate));
    }
  }

  // 6. Merge: pieces of one person split by depth gaps. Two person-like pieces close
  // together on the floor (one person cut in two by something in front) first.
  auto groundDistance = [] (const PersonPartStats &a, const PersonPartStats &b) {
    return std::hypot (a.latMean () - b.latMean (), a.fwdMean () - b.fwdMean ());
  };
  for (bool merged = true; merged;)
  {
    merged = false;
    for (std::size_t i = 0; i < people.size () && !merged; ++i)
      for (std::size_t j = i + 1; j < people.size () && !merged; ++j)
      {
        if (groundDistance (people[i].stats, people[j].stats) >= merge_distance_)
          continue;
        // Never undo a cut: parts of one cluster were found to be two people.
        bool same_cluster = false;
        for (const auto &a : people[i].parts)
          for (const auto &b : people[j].parts)
            same_cluster = same_cluster || a.cluster == b.cluster;
        if (same_cluster)
          continue;
        Candidate both;
        both.parts = people[i].parts;
        both.parts.insert (both.parts.end (), people[j].parts.begin (), people[j].parts.end ());
        measure (both.parts, both.stats);
        if (verdict (both.parts, both.stats) != PersonVerdict::kPerson)
          continue;
        both.verdict = PersonVerdict::kPerson;
        both.split = people[i].split || people[j].split;
        both.pieces = people[i].pieces + people[j].pieces;
        people[i] = std::move (both);
        people.erase (people.begin () + j);
        merged = true;
      }
  }
  // Small pieces, largest first, join the nearest person they touch in the image (a hand
  // held out in front of the arm) or lie in front of or behind (overlapping directions
  // from the camera: a leg seen below a chair). Decisions use each person's own
  // statistics; a piece once merged lets the next ones touch it.
  std::sort (leftovers.begin (), leftovers.end (),
             [] (const Candidate &a, const Candidate &b) { return a.stats.area > b.stats.area; });
  std::vector<int> cell_person (grid.size (), -1);
  auto claimCells = [&] (const std::vector<PersonPart> &parts, int k) {
    for (const auto &part : parts)
      for (int q = cluster_start[part.cluster]; q < cluster_start[part.cluster + 1]; ++q)
      {
        const int c = cluster_cells[q];
        if (grid[c].lat >= part.lo && grid[c].lat < part.hi)
          cell_person[c] = k;
      }
  };
  for (int k = 0; k < static_cast<int> (people.size ()); ++k)
    claimCells (people[k].parts, k);
  std::vector<PersonPartStats> own (people.size ());
  for (std::size_t k = 0; k < people.size (); ++k)
    own[k] = people[k].stats;
  std::vector<unsigned char> touches (people.size ());
  bool any_merged = false;
  std::vector<unsigned char> merged_into (people.size (), 0);
  for (auto &piece : leftovers)
  {
    const PersonPartStats &p = piece.stats;
    if (piece.verdict == PersonVerdict::kTooTall || p.width > 0.5f * max_width_)
      continue;  // walls, shelves, desks
    std::fill (touches.begin (), touches.end (), 0);
    for (const auto &part : piece.parts)
      for (int q = cluster_start[part.cluster]; q < cluster_start[part.cluster + 1]; ++q)
      {
        const int c = cluster_cells[q];
        if (grid[c].lat < part.lo || grid[c].lat >= part.hi)
          continue;
        const int cu = c % cw, cv = c / cw;
        for (const auto &d : kAllNeighbours)
        {
          const int nu = cu + d[0], nv = cv + d[1];
          if (nu >= 0 && nu < cw && nv >= 0 && nv < ch && cell_person[nv * cw + nu] >= 0)
            touches[cell_person[nv * cw + nu]] = 1;
        }
      }
    int best = -1;
    float best_distance = merge_reach_;
    for (int k = 0; k < static_cast<int> (people.size ()); ++k)
    {
      const PersonPartStats &q = own[k];
      // Not above the person's top, unless that top is hidden behind something nearer.
      const bool hidden_top = 2 * q.crown_hidden >= q.crown && q.crown > 0;
      if (p.area > 0.5 * q.area || p.top > (hidden_top ? q.bottom + max_top_ : q.top + 0.1f))
        continue;
      const float overlap = std::min (p.az_max, q.az_max) - std::max (p.az_min, q.az_min);
      if (!touches[k] && overlap < 0.5f * (p.az_max - p.az_min))
        continue;
      const float distance = groundDistance (p, q);
      if (distance <= best_distance)
      {
        best = k;
        best_distance = distance;
      }
    }
    if (best < 0)
      continue;
    Candidate &person = people[best];
    person.parts.insert (person.parts.end (), piece.parts.begin (), piece.parts.end ());
    person.pieces += piece.pieces;
    claimCells (piece.parts, best);
    merged_into[best] = 1;
    any_merged = true;
  }
  if (any_merged)
    for (std::size_t k = 0; k < people.size (); ++k)
      if (merged_into[k])
      {
        measure (people[k].parts, people[k].stats);
        people[k].stats.top = std::max (own[k].top, people[k].stats.top);
      }

  // 8. Full resolution. A pixel in the block of one of the person's cells, or of a free
  // cell next to them, belongs to the person when its depth lies within the gap of the
  // depths of the person's cells around it: a test per pixel, so that what costs the
  // most at full resolution (following connections pixel by pixel) is left to the mesh
  // segmentation that runs on the persons' pixels anyway.
  std::vector<int> cell_stamp (grid.size (), -1);
  std::vector<float> zlo (grid.size ()), zhi (grid.size ());
  std::vector<int> candidates;
  std::vector<int> counts (people.size (), 0);
  std::vector<std::vector<int>> found (people.size ());
  std::vector<Eigen::Vector3d> sums (people.size (), Eigen::Vector3d::Zero ());
  for (int k = 0; k < static_cast<int> (people.size ()); ++k)
  {
    const Candidate &person = people[k];
    candidates.clear ();
    bool bounded = false;
    for (const auto &part : person.parts)
    {
      bounded = bounded || std::isfinite (part.lo) || std::isfinite (part.hi);
      for (int q = cluster_start[part.cluster]; q < cluster_start[part.cluster + 1]; ++q)
      {
        const int c = cluster_cells[q];
        if (cell_person[c] != k)
          continue;
        const float z = grid[c].z;
        const int cu = c % cw, cv = c / cw;
        for (int dv = -1; dv <= 1; ++dv)
          for (int du = -1; du <= 1; ++du)
          {
            const int nu = cu + du, nv = cv + dv;
            if (nu < 0 || nu >= cw || nv < 0 || nv >= ch)
              continue;
            const int j = nv * cw + nu;
            if (cell_person[j] >= 0 && cell_person[j] != k)
              continue;
            if (cell_stamp[j] != k)
            {
              cell_stamp[j] = k;
              zlo[j] = zhi[j] = z;
              candidates.push_back (j);
            }
            else
            {
              zlo[j] = std::min (zlo[j], z);
              zhi[j] = std::max (zhi[j], z);
            }
          }
      }
    }
    // Cells in raster order, their pixels row by row: the indices come out sorted.
    std::sort (candidates.begin (), candidates.end ());
    const auto label = static_cast<std::uint32_t> (k);
    auto &indices = found[k];
    indices.reserve (candidates.size () * step * step);
    Eigen::Vector3d &sum = sums[k];
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
          const float lo = zlo[c] - detail::personDepthGap (zlo[c], coarse_spacing, max_slope_, noise, min_gap_);
          const float hi = zhi[c] + detail::personDepthGap (zhi[c], coarse_spacing, max_slope_, noise, min_gap_);
          Eigen::Vector3f block_sum = Eigen::Vector3f::Zero ();
          for (int u = u0; u < u1; ++u)
          {
            const int i = v * width + u;
            const PointT &p = cloud[i];
            // The depth test first: it also rejects a NaN depth; x + y is finite only if both are.
            if (!(p.z >= lo && p.z <= hi) || labels[i].label != kUnlabelled || !std::isfinite (p.x + p.y) ||
                !(fake_indices_ || selected[i]) || !(p.z > 0.f))
              continue;
            if (with_floor && heightOf (p) < floorMargin (p.z))
              continue;
            if (bounded)
            {
              const float lat = lateral.dot (p.getVector3fMap ());
              bool inside = false;
              for (const auto &part : person.parts)
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
    counts[k] = static_cast<int> (indices.size ());
  }

  // Largest first; ties: lowest first index.
  std::vector<int> order;
  for (int k = 0; k < static_cast<int> (people.size ()); ++k)
    if (counts[k] > 0)
      order.push_back (k);
  std::sort (order.begin (), order.end (), [&] (int a, int b) {
    return counts[a] != counts[b] ? counts[a] > counts[b] : found[a].front () < found[b].front ();
  });
  persons.resize (order.size ());
  std::vector<float> depths;
  for (std::size_t r = 0; r < order.size (); ++r)
  {
    const int k = order[r];
    persons[r].header = cloud.header;
    persons[r].indices.swap (found[k]);
    for (const auto i : persons[r].indices)
      labels[i].label = static_cast<std::uint32_t> (r);

    const Candidate &person = people[k];
    const PersonPartStats &s = person.stats;
    PersonInfo info;
    info.points = counts[k];
    info.centroid = (sums[k] / static_cast<double> (counts[k])).cast<float> ();
    info.ground = with_floor ? Eigen::Vector3f (info.centroid - (normal.dot (info.centroid) + offset) * normal)
                             : info.centroid;
    depths.clear ();
    for (const auto &part : person.parts)
      for (int q = cluster_start[part.cluster]; q < cluster_start[part.cluster + 1]; ++q)
        if (cell_person[cluster_cells[q]] == k)
          depths.push_back (grid[cluster_cells[q]].z);
    std::nth_element (depths.begin (), depths.begin () + depths.size () / 2, depths.end ());
    info.distance = depths[depths.size () / 2];
    info.top = s.top;
    info.bottom = s.bottom;
    info.width = s.width;
    info.area = static_cast<float> (s.area);
    info.hand_pixels = hand_area_ * fx * fy / (info.distance * info.distance);
    info.too_far = info.hand_pixels < min_hand_pixels_;
    info.on_floor = with_floor;
    info.split = person.split;
    info.pieces = person.pieces;
    info.border = s.border;
    infos_.push_back (info);
  }
  deinitCompute ();
}

#define PCL_INSTANTIATE_PersonSegmentation(T) template class PCL_EXPORTS agex::PersonSegmentation<T>;
