#include <agex/simulation/depth_frame_statistics.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace agex
{
namespace
{
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN ();
constexpr std::size_t kMaxSamplesPerBin = 400000;  ///< bounds memory on long runs

double
percentile (std::vector<float> values, double p)
{
  if (values.empty ())
    return kNaN;
  const std::size_t k = std::min (values.size () - 1, static_cast<std::size_t> (p * values.size ()));
  std::nth_element (values.begin (), values.begin () + static_cast<std::ptrdiff_t> (k), values.end ());
  return values[k];
}
}  // namespace

void
DepthFrameStatistics::setDepthBins (double bin_width, double max_depth)
{
  if (!(bin_width >= 0.05 && bin_width <= 5.0) || !(max_depth > bin_width && max_depth <= 100.0))
    throw std::invalid_argument ("DepthFrameStatistics: depth bins need 0.05 <= width <= 5 m < max depth <= 100 m");
  if (!steps_.empty ())
    throw std::invalid_argument ("DepthFrameStatistics: depth bins are set before the first frame");
  bin_width_ = bin_width;
  max_depth_ = max_depth;
}

void
DepthFrameStatistics::setPatchSize (int pixels)
{
  if (pixels < 3 || pixels > 31 || pixels % 2 == 0)
    throw std::invalid_argument ("DepthFrameStatistics: patch size " + std::to_string (pixels) + " is not odd 3-31");
  patch_ = pixels;
}

void
DepthFrameStatistics::setBandWidth (int pixels)
{
  if (pixels < 1 || pixels > 10)
    throw std::invalid_argument ("DepthFrameStatistics: band width " + std::to_string (pixels) + " is not 1-10");
  band_ = pixels;
}

void
DepthFrameStatistics::ensureBins ()
{
  if (steps_.empty ())
  {
    const std::size_t n = static_cast<std::size_t> (std::ceil (max_depth_ / bin_width_));
    steps_.resize (n);
    noise_.resize (n);
  }
}

int
DepthFrameStatistics::binOf (double z) const
{
  if (!(z > 0.0) || z >= max_depth_)
    return -1;
  return std::min (static_cast<int> (z / bin_width_), static_cast<int> (steps_.size ()) - 1);
}

void
DepthFrameStatistics::add (const pcl::PointCloud<pcl::PointXYZ> &cloud, const std::vector<std::uint8_t> &mask)
{
  if (cloud.height < 2 || cloud.width < 2 || cloud.points.size () != static_cast<std::size_t> (cloud.width) * cloud.height)
    throw std::invalid_argument ("DepthFrameStatistics: the cloud is not organized");
  const int w = static_cast<int> (cloud.width), h = static_cast<int> (cloud.height);
  const std::size_t n = cloud.points.size ();
  if (!mask.empty () && mask.size () != n)
    throw std::invalid_argument ("DepthFrameStatistics: the mask has " + std::to_string (mask.size ()) +
                                 " pixels, the cloud " + std::to_string (n));
  ensureBins ();
  std::vector<float> z (n);
  for (std::size_t i = 0; i < n; ++i)
  {
    const float d = cloud.points[i].z;
    z[i] = std::isfinite (d) && d > 0.0f ? d : std::numeric_limits<float>::quiet_NaN ();
  }
  auto at = [&] (int u, int v) { return z[static_cast<std::size_t> (v) * w + u]; };
  auto person = [&] (int u, int v) { return !mask.empty () && mask[static_cast<std::size_t> (v) * w + u] != 0; };

  // Smallest steps between 4-neighbours.
  for (int v = 0; v + 1 < h; ++v)
    for (int u = 0; u + 1 < w; ++u)
    {
      const float a = at (u, v);
      if (!std::isfinite (a))
        continue;
      for (const float b : {at (u + 1, v), at (u, v + 1)})
      {
        if (!std::isfinite (b))
          continue;
        // Stored as step / z^2, so that the depths within a bin compare alike.
        const float d = std::abs (a - b), zm = 0.5f * (a + b);
        const int bin = binOf (zm);
        if (d > 1e-5f && d < 0.1f * a && bin >= 0 && steps_[static_cast<std::size_t> (bin)].size () < kMaxSamplesPerBin)
          steps_[static_cast<std::size_t> (bin)].push_back (d / (zm * zm));
      }
    }

  // Flat patches off the person: plane fit residual.
  const int r = patch_ / 2;
  for (int v0 = r; v0 + r < h; v0 += patch_)
    for (int u0 = r; u0 + r < w; u0 += patch_)
    {
      Eigen::Vector3d mean = Eigen::Vector3d::Zero ();
      Eigen::Matrix3d second = Eigen::Matrix3d::Zero ();
      bool ok = true;
      const float zc = at (u0, v0);
      for (int v = v0 - r; ok && v <= v0 + r; ++v)
        for (int u = u0 - r; ok && u <= u0 + r; ++u)
        {
          const float zi = at (u, v);
          if (!std::isfinite (zi) || person (u, v) || std::abs (zi - zc) > 0.1f + 0.05f * zc)
          {
            ok = false;
            break;
          }
          const pcl::PointXYZ &p = cloud.points[static_cast<std::size_t> (v) * w + u];
          const Eigen::Vector3d q (p.x, p.y, p.z);
          mean += q;
          second += q * q.transpose ();
        }
      const int bin = binOf (zc);
      if (!ok || bin < 0 || noise_[static_cast<std::size_t> (bin)].size () >= kMaxSamplesPerBin)
        continue;
      const double count = static_cast<double> (patch_ * patch_);
      mean /= count;
      const Eigen::Matrix3d cov = second / count - mean * mean.transpose ();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig (cov);
      const double rms = std::sqrt (std::max (0.0, eig.eigenvalues ()[0]));
      // Not flat (an edge or a corner the depth test let through): skip.
      if (rms < 0.03)
        noise_[static_cast<std::size_t> (bin)].push_back (static_cast<float> (rms));
    }

  if (mask.empty ())
    return;
  // Distance (in 4-neighbour steps, up to band_) of every pixel to the mask's edge.
  std::vector<int> dist (n, band_ + 1);
  std::vector<std::size_t> frontier;
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
    {
      const bool here = person (u, v);
      const int du[4] = {1, -1, 0, 0}, dv[4] = {0, 0, 1, -1};
      for (int q = 0; q < 4; ++q)
      {
        const int uu = u + du[q], vv = v + dv[q];
        if (uu >= 0 && vv >= 0 && uu < w && vv < h && person (uu, vv) != here)
        {
          dist[static_cast<std::size_t> (v) * w + u] = 0;
          frontier.push_back (static_cast<std::size_t> (v) * w + u);
          break;
        }
      }
    }
  for (int d = 1; d <= band_; ++d)
  {
    std::vector<std::size_t> next;
    for (const std::size_t i : frontier)
    {
      const int u = static_cast<int> (i % w), v = static_cast<int> (i / w);
      const int du[4] = {1, -1, 0, 0}, dv[4] = {0, 0, 1, -1};
      for (int q = 0; q < 4; ++q)
      {
        const int uu = u + du[q], vv = v + dv[q];
        const std::size_t j = static_cast<std::size_t> (vv) * w + uu;
        if (uu >= 0 && vv >= 0 && uu < w && vv < h && dist[j] > d)
        {
          dist[j] = d;
          next.push_back (j);
        }
      }
    }
    frontier.swap (next);
  }
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
    {
      const std::size_t i = static_cast<std::size_t> (v) * w + u;
      if (dist[i] > band_)
        continue;
      const float zi = z[i];
      if (person (u, v))
      {
        ++band_pixels_;
        band_holes_ += !std::isfinite (zi);
      }
      if (!std::isfinite (zi))
        continue;
      // Flying: valid neighbours both nearer and farther by more than 3 cm + 2%.
      const float t = 0.03f + 0.02f * zi;
      bool nearer = false, farther = false;
      for (int dv = -1; dv <= 1; ++dv)
        for (int du = -1; du <= 1; ++du)
        {
          const int uu = u + du, vv = v + dv;
          if (uu < 0 || vv < 0 || uu >= w || vv >= h)
            continue;
          const float zj = at (uu, vv);
          nearer = nearer || (std::isfinite (zj) && zj < zi - t);
          farther = farther || (std::isfinite (zj) && zj > zi + t);
        }
      ++near_valid_;
      near_flying_ += nearer && farther;
      // Steps from the person to the pixels beside it.
      if (!person (u, v) || dist[i] != 0)
        continue;
      const int du[4] = {1, -1, 0, 0}, dv[4] = {0, 0, 1, -1};
      for (int q = 0; q < 4; ++q)
      {
        const int uu = u + du[q], vv = v + dv[q];
        if (uu < 0 || vv < 0 || uu >= w || vv >= h || person (uu, vv) || !std::isfinite (at (uu, vv)))
          continue;
        const double step = std::abs (at (uu, vv) - zi);
        std::size_t b = 0;
        while (step > kStepEdges[b] && b + 1 < kStepEdges.size ())
          ++b;
        ++step_hist_[b];
        ++step_count_;
      }
    }
}

double
DepthFrameStatistics::depthStep (int bin) const
{
  const auto &s = steps_.at (static_cast<std::size_t> (bin));
  return s.size () < 50 ? kNaN : percentile (s, 0.1) * binCentre (bin) * binCentre (bin);
}

double
DepthFrameStatistics::flatNoise (int bin) const
{
  const auto &s = noise_.at (static_cast<std::size_t> (bin));
  return s.size () < 10 ? kNaN : percentile (s, 0.5);
}

std::array<double, DepthFrameStatistics::kStepEdges.size ()>
DepthFrameStatistics::silhouetteStepHistogram () const
{
  std::array<double, kStepEdges.size ()> f{};
  for (std::size_t b = 0; b < f.size (); ++b)
    f[b] = step_count_ ? static_cast<double> (step_hist_[b]) / step_count_ : kNaN;
  return f;
}

double
DepthFrameStatistics::silhouetteHoleRate () const
{
  return band_pixels_ ? static_cast<double> (band_holes_) / band_pixels_ : kNaN;
}

double
DepthFrameStatistics::silhouetteFlyingRate () const
{
  return near_valid_ ? static_cast<double> (near_flying_) / near_valid_ : kNaN;
}

double
DepthFrameStatistics::fittedDisparityConstant () const
{
  // step = z^2 / k: the mean of step / z^2 over the bins, each bin alike.
  double sum = 0.0;
  int bins = 0;
  for (int b = 0; b < depthBins (); ++b)
  {
    const double s = depthStep (b), z = binCentre (b);
    if (!std::isfinite (s))
      continue;
    sum += s / (z * z);
    ++bins;
  }
  return bins < 2 || sum <= 0.0 ? kNaN : bins / sum;
}

std::string
DepthFrameStatistics::report (const std::string &name) const
{
  std::ostringstream out;
  out << std::fixed << std::setprecision (4);
  out << name << ": depth_m step_m flat_rms_m flat_patches\n";
  for (int b = 0; b < depthBins (); ++b)
    if (std::isfinite (depthStep (b)) || std::isfinite (flatNoise (b)))
      out << name << ": " << binCentre (b) << " " << depthStep (b) << " " << flatNoise (b) << " " << flatPatches (b)
          << "\n";
  out << name << ": fitted 8fb (step = z^2 / 8fb) = " << fittedDisparityConstant () << " m\n";
  if (step_count_)
  {
    const auto f = silhouetteStepHistogram ();
    out << name << ": silhouette steps (" << step_count_ << ") <1cm,1-3,3-10,10-30,30-100,100-300,>300cm:";
    for (const double x : f)
      out << " " << x;
    out << "\n";
  }
  out << name << ": silhouette hole rate " << silhouetteHoleRate () << ", flying rate " << silhouetteFlyingRate ()
      << "\n";
  return out.str ();
}
}  // namespace agex
