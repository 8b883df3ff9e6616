// agex::PartModeEstimation: mean shift over part probabilities (Shotton et al. Sec. 4).

#include <agex/classification/part_modes.h>

#include <agex/common/statistics.h>

#include <pcl/console/print.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <unordered_map>

namespace agex
{
namespace
{
struct Sample
{
  Eigen::Vector3f x;
  float w;    ///< p z^2
  float p;
  int index;      ///< into the label cloud
  int slot = -1;  ///< into the body's pixels, for a sample of one
};

std::int64_t
cellKey (int i, int j, int k)
{
  // 21 bits per axis: +-1M cells, far beyond any scene at centimetre cells.
  auto b = [] (int v) { return static_cast<std::int64_t> (v + (1 << 20)) & ((std::int64_t (1) << 21) - 1); };
  return (b (i) << 42) | (b (j) << 21) | b (k);
}

/** The cell of coordinate v, within cellKey's range: far-off points share the edge cells
  * rather than overflow an int. */
int
cellOf (float v, float size)
{
  return clampedInt (std::floor (v / size), -(1 << 20), (1 << 20) - 1);
}

/** The samples' indices grouped by cubic cell of the given size: cells in key order, each
  * cell's indices ascending. */
std::vector<std::vector<int>>
groupByCell (const std::vector<Sample> &samples, float size)
{
  std::vector<std::pair<std::int64_t, int>> keyed;
  keyed.reserve (samples.size ());
  for (std::size_t i = 0; i < samples.size (); ++i)
  {
    const Eigen::Vector3f &x = samples[i].x;
    keyed.emplace_back (cellKey (cellOf (x.x (), size), cellOf (x.y (), size), cellOf (x.z (), size)),
                        static_cast<int> (i));
  }
  std::sort (keyed.begin (), keyed.end ());
  std::vector<std::vector<int>> cells;
  for (std::size_t i = 0; i < keyed.size (); ++i)
  {
    if (i == 0 || keyed[i].first != keyed[i - 1].first)
      cells.emplace_back ();
    cells.back ().push_back (keyed[i].second);
  }
  return cells;
}

/** Points hashed into cubic cells of a given size; cells numbered 0..cellCount () - 1. */
class Grid
{
public:
  Grid (const std::vector<Sample> &samples, float cell) : cell_ (cell)
  {
    for (std::size_t i = 0; i < samples.size (); ++i)
    {
      const Eigen::Vector3i c = coords (samples[i].x);
      const auto inserted = ids_.emplace (cellKey (c.x (), c.y (), c.z ()), static_cast<int> (cells_.size ()));
      if (inserted.second)
        cells_.emplace_back ();
      cells_[static_cast<std::size_t> (inserted.first->second)].push_back (static_cast<int> (i));
    }
  }
  Eigen::Vector3i coords (const Eigen::Vector3f &x) const
  {
    return Eigen::Vector3i (cellOf (x.x (), cell_), cellOf (x.y (), cell_), cellOf (x.z (), cell_));
  }
  std::size_t cellCount () const { return cells_.size (); }
  const std::vector<int> &cell (int id) const { return cells_[static_cast<std::size_t> (id)]; }
  /** Calls fn (cell id) for every non-empty cell of the 27 around x. */
  template <typename Fn>
  void aroundCells (const Eigen::Vector3f &x, Fn fn) const
  {
    const Eigen::Vector3i c = coords (x);
    for (int i = -1; i <= 1; ++i)
      for (int j = -1; j <= 1; ++j)
        for (int k = -1; k <= 1; ++k)
        {
          const auto it = ids_.find (cellKey (c.x () + i, c.y () + j, c.z () + k));
          if (it != ids_.end ())
            fn (it->second);
        }
  }
  /** Calls fn (sample index) for every sample in the 27 cells around x. */
  template <typename Fn>
  void around (const Eigen::Vector3f &x, Fn fn) const
  {
    aroundCells (x, [&] (int id) {
      for (const int s : cells_[static_cast<std::size_t> (id)])
        fn (s);
    });
  }

private:
  float cell_;
  std::unordered_map<std::int64_t, int> ids_;
  std::vector<std::vector<int>> cells_;
};

/** 2^t for t in [-126, 0]: Cephes' exp2f polynomial on [-0.5, 0.5] (relative error below
  * 2e-7), inline and branch-free so the kernel loop below vectorises, which a call to
  * std::exp does not. */
inline float
exp2NonPositive (float t)
{
  const int n = static_cast<int> (t - 0.5f);  // rounds to nearest: truncation of t - 0.5 <= 0
  const float f = t - static_cast<float> (n);
  float p = 1.535336188319500e-4f;
  p = p * f + 1.339887440266574e-3f;
  p = p * f + 9.618437357674640e-3f;
  p = p * f + 5.550332471162809e-2f;
  p = p * f + 2.402264791363012e-1f;
  p = p * f + 6.931472028550421e-1f;
  p = p * f + 1.f;
  const std::int32_t bits = (n + 127) * (1 << 23);
  float scale;
  std::memcpy (&scale, &bits, sizeof scale);
  return p * scale;
}

/** Sum of n floats in eight interleaved lanes (a fixed order, so deterministic), which the
  * compiler vectorises; a plain float sum it may not reorder. */
float
laneSum (const float *a, std::size_t n)
{
  constexpr std::size_t kLanes = 8;
  float lanes[kLanes] = {};
  std::size_t i = 0;
  for (; i + kLanes <= n; i += kLanes)
    for (std::size_t l = 0; l < kLanes; ++l)
      lanes[l] += a[i + l];
  for (std::size_t l = 0; i < n; ++i, ++l)
    lanes[l] += a[i];
  return ((lanes[0] + lanes[1]) + (lanes[2] + lanes[3])) + ((lanes[4] + lanes[5]) + (lanes[6] + lanes[7]));
}

/** Per atom i: its kernel weight k = w exp (-d^2 / b^2) (0 beyond sqrt (cut2)) and k times its
  * offset from x. exponent: log2 (e) / b^2. Parameters rather than locals so that restrict
  * holds (GCC ignores it on locals) and the loop vectorises without overlap checks. */
void
kernelWeights (const float *__restrict ax, const float *__restrict ay, const float *__restrict az,
               const float *__restrict aw, std::size_t n, const Eigen::Vector3f &x, float exponent, float cut2,
               float *__restrict kx, float *__restrict ky, float *__restrict kz, float *__restrict k)
{
  const float x0 = x.x (), y0 = x.y (), z0 = x.z ();
  for (std::size_t i = 0; i < n; ++i)
  {
    const float dx = ax[i] - x0, dy = ay[i] - y0, dz = az[i] - z0;
    const float d2 = dx * dx + dy * dy + dz * dz;
    // Beyond the cut the weight is 0; the exponent is taken of the clamped distance so that
    // it stays a finite number to multiply by that 0.
    const float inside = std::max (0.f, std::copysign (1.f, cut2 - d2));
    const float w = inside * aw[i] * exp2NonPositive (-std::min (d2, cut2) * exponent);
    k[i] = w;
    kx[i] = w * dx;
    ky[i] = w * dy;
    kz[i] = w * dz;
  }
}

/** The atoms of the 27 kernel-grid cells around a mean-shift point, copied into plain arrays
  * and kept while the point stays in its cell (a path moves millimetres per step, so most
  * steps reuse them): a step is then two vectorised passes over contiguous floats instead of
  * 27 hash lookups and scattered reads. */
class KernelNeighbourhood
{
public:
  KernelNeighbourhood (const Grid &grid, const std::vector<Sample> &atoms, float bandwidth)
    : grid_ (grid), atoms_ (atoms), exponent_ (1.4426950409f / (bandwidth * bandwidth)), cut2_ (9.f * bandwidth * bandwidth)
  {
  }

  /** One mean-shift step from x: the weighted mean of the atoms within 3 bandwidths under
    * the Gaussian kernel. \return false if no atom is within reach */
  bool step (const Eigen::Vector3f &x, Eigen::Vector3f &next)
  {
    const Eigen::Vector3i cell = grid_.coords (x);
    if (!filled_ || cell != cell_)
      gather (x, cell);
    const std::size_t n = ax_.size ();
    kernelWeights (ax_.data (), ay_.data (), az_.data (), aw_.data (), n, x, exponent_, cut2_, kx_.data (), ky_.data (),
                   kz_.data (), k_.data ());
    const float *kx = kx_.data (), *ky = ky_.data (), *kz = kz_.data (), *k = k_.data ();
    const float den = laneSum (k, n);
    if (!(den > 0.f))
      return false;
    next = x + Eigen::Vector3f (laneSum (kx, n), laneSum (ky, n), laneSum (kz, n)) / den;
    return true;
  }

private:
  void gather (const Eigen::Vector3f &x, const Eigen::Vector3i &cell)
  {
    ax_.clear ();
    ay_.clear ();
    az_.clear ();
    aw_.clear ();
    grid_.around (x, [&] (int a) {
      const Sample &atom = atoms_[static_cast<std::size_t> (a)];
      ax_.push_back (atom.x.x ());
      ay_.push_back (atom.x.y ());
      az_.push_back (atom.x.z ());
      aw_.push_back (atom.w);
    });
    kx_.resize (ax_.size ());
    ky_.resize (ax_.size ());
    kz_.resize (ax_.size ());
    k_.resize (ax_.size ());
    cell_ = cell;
    filled_ = true;
  }

  const Grid &grid_;
  const std::vector<Sample> &atoms_;
  float exponent_, cut2_;  ///< log2(e) / b^2 (exp2 of its product is the kernel), (3 b)^2
  Eigen::Vector3i cell_ = Eigen::Vector3i::Zero ();
  bool filled_ = false;
  std::vector<float> ax_, ay_, az_, aw_, kx_, ky_, kz_, k_;
};
}  // namespace

bool
PartModeEstimation::compute (const pcl::PointCloud<BodyPartLabelPoint> &labels, std::vector<PartMode> &modes) const
{
  return computeFrom (labels, nullptr, modes);
}

bool
PartModeEstimation::compute (const pcl::PointCloud<BodyPartLabelPoint> &labels, const pcl::Indices &pixels,
                             std::vector<PartMode> &modes) const
{
  return computeFrom (labels, &pixels, modes);
}

bool
PartModeEstimation::computeFrom (const pcl::PointCloud<BodyPartLabelPoint> &labels, const pcl::Indices *pixels,
                                 std::vector<PartMode> &modes) const
{
  modes.clear ();
  const PartModeParams &P = params_;
  for (int c = 0; c < kLabelPartCount; ++c)
    // Bandwidths from 0.1 mm to 10 m: the kernel's exponent 1 / b^2 stays a finite float.
    if (!(P.bandwidth[c] >= 1e-4f && P.bandwidth[c] <= 10.f) || !(P.reference_area[c] > 0.f) ||
        !std::isfinite (P.reference_area[c]))
    {
      PCL_ERROR ("[agex::PartModeEstimation::compute] Bandwidths must lie in 0.0001-10 m and reference areas be "
                 "finite and positive.\n");
      return false;
    }
  if (!(P.fx > 0.f) || !(P.fy > 0.f) || !std::isfinite (P.fx) || !std::isfinite (P.fy) || P.max_iterations < 1 ||
      !(P.convergence > 0.f) || !(P.contact_radius > 0.f) || !std::isfinite (P.probability_threshold) ||
      !(P.elongation >= 1.f) || P.min_support < 1 || P.pixel_step < 1 || P.pixel_step > 64)
  {
    PCL_ERROR ("[agex::PartModeEstimation::compute] Invalid parameters (focal lengths, iterations, convergence, "
               "contact radius, threshold, elongation >= 1, min support >= 1, pixel step 1-64).\n");
    return false;
  }

  // The body: every labelled pixel with a finite point.
  Eigen::Vector3d body_sum = Eigen::Vector3d::Zero ();
  std::size_t body_count = 0;
  std::vector<int> body;
  const std::size_t width = labels.width, step = static_cast<std::size_t> (P.pixel_step);
  const bool stepped = step > 1 && labels.isOrganized () && width > 0;
  const auto visit = [&] (std::size_t i) {
    const auto &q = labels[i];
    if (q.label >= 0 && std::isfinite (q.x) && std::isfinite (q.y) && std::isfinite (q.z))
    {
      body_sum += q.getVector3fMap ().cast<double> ();
      ++body_count;
      body.push_back (static_cast<int> (i));
    }
  };
  // Rows and columns stepped, not each pixel's index divided: the divisions were half of
  // this function's time on a 640x480 frame.
  if (pixels)
  {
    // The given pixels on the step's grid, in raster order: the scan below, without the
    // rest of the frame.
    std::vector<std::size_t> order;
    order.reserve (pixels->size () / (stepped ? step * step : 1));
    for (const auto index : *pixels)
    {
      if (index < 0 || static_cast<std::size_t> (index) >= labels.size () ||
          (stepped && ((static_cast<std::size_t> (index) % width) % step || (static_cast<std::size_t> (index) / width) % step)))
        continue;
      order.push_back (static_cast<std::size_t> (index));
    }
    std::sort (order.begin (), order.end ());
    order.erase (std::unique (order.begin (), order.end ()), order.end ());
    for (const std::size_t i : order)
      visit (i);
  }
  else if (stepped)
  {
    for (std::size_t row = 0; row < labels.size () / width; row += step)
      for (std::size_t col = 0; col < width; col += step)
        visit (row * width + col);
  }
  else
  {
    for (std::size_t i = 0; i < labels.size (); ++i)
      visit (i);
  }
  if (body_count == 0)
    return true;
  const Eigen::Vector3f body_centroid = (body_sum / static_cast<double> (body_count)).cast<float> ();
  // The body's pixels in cells of the contact radius, for every mode's base below.
  std::vector<Sample> body_points;
  body_points.reserve (body.size ());
  for (const int i : body)
    body_points.push_back ({labels[static_cast<std::size_t> (i)].getVector3fMap (), 0.f, 0.f, i});
  const Grid body_grid (body_points, P.contact_radius);
  std::vector<unsigned> support_stamp (body_points.size (), 0u), touched_stamp (body_points.size (), 0u);
  std::vector<unsigned> cell_stamp (body_grid.cellCount (), 0u);  // cell_left is current for this mode
  std::vector<int> cell_left (body_grid.cellCount (), 0);         // body pixels neither support nor touching
  unsigned visit_stamp = 0;
  const float pixel_area = (stepped ? static_cast<float> (step * step) : 1.f) / (P.fx * P.fy);

  for (int part = 0; part < kLabelPartCount; ++part)
  {
    if (!P.parts[part])
      continue;
    const float b = P.bandwidth[part];
    std::vector<Sample> samples;
    for (std::size_t k = 0; k < body.size (); ++k)
    {
      const auto &q = labels[static_cast<std::size_t> (body[k])];
      const float p = q.probability (part);
      // A finite weight (an absurd depth could overflow z^2): every mean below stays finite.
      if (std::isfinite (p) && p >= P.probability_threshold && p > 0.f && std::isfinite (p * q.z * q.z))
        samples.push_back ({q.getVector3fMap (), p * q.z * q.z, p, body[k], static_cast<int> (k)});
    }
    if (samples.empty ())
      continue;
    // The density is summed over atoms, not pixels: the samples' weighted means in cells a
    // quarter of the bandwidth wide. A kernel that wide hardly changes across a cell, and the
    // cost no longer grows with the resolution (a 640x480 hand has ten times a 144x176 one's
    // pixels, not ten times its atoms).
    std::vector<Sample> atoms;
    for (const auto &cell : groupByCell (samples, 0.25f * b))
    {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero ();
      double w = 0.0;
      for (const int i : cell)
      {
        sum += samples[static_cast<std::size_t> (i)].x.cast<double> () * samples[static_cast<std::size_t> (i)].w;
        w += samples[static_cast<std::size_t> (i)].w;
      }
      if (w > 0.0)
        atoms.push_back ({(sum / w).cast<float> (), static_cast<float> (w), 0.f, -1});
    }
    const Grid kernel_grid (atoms, 3.f * b);
    // Seeds: one per bandwidth cell, in key order (deterministic).
    const std::vector<std::vector<int>> seed_cells = groupByCell (samples, b);
    struct Found
    {
      Eigen::Vector3f x;
      std::vector<int> samples;
    };
    std::vector<Found> found;
    KernelNeighbourhood neighbourhood (kernel_grid, atoms, b);
    // Basins of attraction: the cells a quarter bandwidth wide in which a path's steps landed,
    // each to the mode the path led to. A later path landing in one of them joins that mode: two
    // paths through the same small cell climb the same hill, and most seeds meet an earlier path
    // within a few steps instead of climbing all the way.
    const float path_cell = 0.25f * b;
    std::unordered_map<std::int64_t, int> basin;
    std::vector<std::int64_t> path;
    const auto pathKey = [&] (const Eigen::Vector3f &p) {
      return cellKey (cellOf (p.x (), path_cell), cellOf (p.y (), path_cell), cellOf (p.z (), path_cell));
    };
    for (const auto &cell : seed_cells)
    {
      Eigen::Vector3d seed = Eigen::Vector3d::Zero ();
      double wsum = 0.0;
      for (const int s : cell)
      {
        seed += samples[s].x.cast<double> () * samples[s].w;
        wsum += samples[s].w;
      }
      Eigen::Vector3f x = (seed / wsum).cast<float> ();
      int joined = -1;
      // Only a path that ends at a mode (converged, or reached one found before) marks its cells:
      // one stopped by the iteration limit or an empty neighbourhood would hand its trail to a
      // point that is no mode.
      bool settled = false;
      path.clear ();
      for (int it = 0; it < P.max_iterations; ++it)
      {
        const std::int64_t key = pathKey (x);
        const auto hit = basin.find (key);
        if (hit != basin.end ())
        {
          joined = hit->second;
          settled = true;
          break;
        }
        path.push_back (key);
        Eigen::Vector3f next;
        if (!neighbourhood.step (x, next))
          break;
        const float step = (next - x).norm ();
        x = next;
        if (step < P.convergence)
        {
          settled = true;
          break;
        }
        // A path that reaches a mode already found ends there: it would climb the same hill.
        if (std::any_of (found.begin (), found.end (), [&] (const Found &f) { return (f.x - x).norm () < 0.1f * b; }))
        {
          settled = true;
          break;
        }
      }
      int into = joined;
      if (into < 0)
      {
        auto same = std::find_if (found.begin (), found.end (), [&] (const Found &f) { return (f.x - x).norm () < 0.5f * b; });
        if (same == found.end ())
        {
          found.push_back ({x, {}});
          into = static_cast<int> (found.size ()) - 1;
        }
        else
          into = static_cast<int> (same - found.begin ());
      }
      found[static_cast<std::size_t> (into)].samples.insert (found[static_cast<std::size_t> (into)].samples.end (), cell.begin (), cell.end ());
      if (settled)
        for (const std::int64_t key : path)
          basin.emplace (key, into);
    }

    std::vector<PartMode> part_modes;
    for (auto &f : found)
    {
      if (static_cast<int> (f.samples.size ()) < P.min_support)
        continue;
      std::sort (f.samples.begin (), f.samples.end ());
      PartMode m;
      m.part = part;
      m.position = f.x;
      double wsum = 0.0, psum = 0.0;
      Eigen::Vector3d mean = Eigen::Vector3d::Zero ();
      for (const int s : f.samples)
      {
        wsum += samples[s].w;
        psum += samples[s].p;
        mean += samples[s].x.cast<double> () * samples[s].w;
        m.support.push_back (samples[s].index);
      }
      mean /= wsum;
      m.mass = static_cast<float> (wsum) * pixel_area;
      m.confidence = m.mass / (m.mass + P.reference_area[part]);
      m.mean_probability = static_cast<float> (psum / static_cast<double> (f.samples.size ()));

      // The base: where the part touches the rest of the body (the labelled pixels outside the
      // support within contact_radius of a supporting pixel: the wrist, the neck, the ankle, a
      // hip the hand rests on), else the body's centroid.
      // Searched from the support outwards (the body pixels in the cells around each
      // supporting pixel), then summed in body order: the same sum as testing every body pixel.
      ++visit_stamp;
      for (const int s : f.samples)
        support_stamp[static_cast<std::size_t> (samples[s].slot)] = visit_stamp;
      std::vector<int> touching;
      const float r2 = P.contact_radius * P.contact_radius;
      // A cell whose body pixels are all support or already touching has nothing left to
      // find: the support's interior is skipped cell by cell, not pixel by pixel.
      const auto untouched = [&] (int c) -> int & {
        if (cell_stamp[static_cast<std::size_t> (c)] != visit_stamp)
        {
          cell_stamp[static_cast<std::size_t> (c)] = visit_stamp;
          int &left = cell_left[static_cast<std::size_t> (c)];
          left = 0;
          for (const int bj : body_grid.cell (c))
            left += support_stamp[static_cast<std::size_t> (bj)] != visit_stamp;
        }
        return cell_left[static_cast<std::size_t> (c)];
      };
      for (const int s : f.samples)
        body_grid.aroundCells (samples[s].x, [&] (int c) {
          int &left = untouched (c);
          if (left == 0)
            return;
          for (const int bj : body_grid.cell (c))
          {
            const auto j = static_cast<std::size_t> (bj);
            if (support_stamp[j] != visit_stamp && touched_stamp[j] != visit_stamp &&
                (body_points[j].x - samples[s].x).squaredNorm () <= r2)
            {
              touched_stamp[j] = visit_stamp;
              touching.push_back (bj);
              --left;
            }
          }
        });
      std::sort (touching.begin (), touching.end ());
      Eigen::Vector3d base_sum = Eigen::Vector3d::Zero ();
      const std::size_t base_count = touching.size ();
      for (const int bj : touching)
        base_sum += body_points[static_cast<std::size_t> (bj)].x.cast<double> ();
      const Eigen::Vector3f base = base_count ? (base_sum / static_cast<double> (base_count)).cast<float> () : body_centroid;
      Eigen::Vector3f away = m.position - base;
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero ();
      for (const int s : f.samples)
      {
        const Eigen::Vector3d d = samples[s].x.cast<double> () - mean;
        cov += samples[s].w * d * d.transpose ();
      }
      cov /= wsum;
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig (cov);
      const Eigen::Vector3d ev = eig.eigenvalues ();  // ascending
      Eigen::Vector3f dir = Eigen::Vector3f::Zero ();
      const bool elongated = ev (2) > 0.0 && ev (2) >= static_cast<double> (P.elongation * P.elongation) * ev (1);
      if (elongated)
      {
        dir = eig.eigenvectors ().col (2).cast<float> ().normalized ();
        if (dir.dot (away) < 0.f)
          dir = -dir;
      }
      else if (away.norm () > 1e-6f)
        dir = away.normalized ();
      else if (ev (2) > 0.0)
        dir = eig.eigenvectors ().col (2).cast<float> ().normalized ();
      m.direction = dir;
      float best = -std::numeric_limits<float>::infinity ();
      for (const int s : f.samples)
      {
        const float t = (samples[s].x - m.position).dot (dir);
        if (t > best)
        {
          best = t;
          m.tip = samples[s].x;
          m.tip_index = samples[s].index;
        }
      }
      part_modes.push_back (std::move (m));
    }
    std::stable_sort (part_modes.begin (), part_modes.end (),
                      [] (const PartMode &a, const PartMode &b) { return a.confidence > b.confidence; });

    modes.insert (modes.end (), std::make_move_iterator (part_modes.begin ()), std::make_move_iterator (part_modes.end ()));
  }
  return true;
}
}  // namespace agex
