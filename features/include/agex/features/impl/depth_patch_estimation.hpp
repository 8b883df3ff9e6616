#pragma once

#include <agex/features/depth_patch_estimation.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

template <typename PointInT, typename PointOutT> float
agex::DepthPatchEstimation<PointInT, PointOutT>::estimateFocalLength (const PointCloudIn &cloud)
{
  if (!cloud.isOrganized ())
    return 0.f;
  const int width = static_cast<int> (cloud.width), height = static_cast<int> (cloud.height);
  // Sums for the two regressions u ~ x/z and v ~ y/z with a shared slope.
  struct Sums
  {
    double n = 0, a = 0, u = 0, aa = 0, au = 0;  // a = x/z, u = column
    double b = 0, v = 0, bb = 0, bv = 0;         // b = y/z, v = row
  };
  auto accumulate = [&] (int step) {
    Sums s;
    for (int row = step / 2; row < height; row += step)
      for (int col = step / 2; col < width; col += step)
      {
        const PointInT &p = cloud (col, row);
        if (!std::isfinite (p.x) || !std::isfinite (p.y) || !std::isfinite (p.z) || !(p.z > 0.f))
          continue;
        const double a = static_cast<double> (p.x) / p.z, b = static_cast<double> (p.y) / p.z;
        s.n += 1;
        s.a += a;
        s.u += col;
        s.aa += a * a;
        s.au += a * col;
        s.b += b;
        s.v += row;
        s.bb += b * b;
        s.bv += b * row;
      }
    return s;
  };
  const long pixels = static_cast<long> (width) * height;
  const int grid_step = std::max (1, static_cast<int> (std::sqrt (static_cast<double> (pixels) / 4096.0)));
  Sums s = accumulate (grid_step);
  if (s.n < 64 && grid_step > 1)
    s = accumulate (1);  // sparse frame: use every pixel
  if (s.n < 3)
    return 0.f;
  // Centred (co)variances; f = (cov(a,u) + cov(b,v)) / (var(a) + var(b)).
  const double var = (s.aa - s.a * s.a / s.n) + (s.bb - s.b * s.b / s.n);
  const double cov = (s.au - s.a * s.u / s.n) + (s.bv - s.b * s.v / s.n);
  // Spread of the viewing-ray slopes: below ~1e-12 per point the points share one ray.
  if (!(var > 1e-12 * s.n))
    return 0.f;
  const double f = cov / var;
  return std::isfinite (f) && f > 0.0 ? static_cast<float> (f) : 0.f;
}

template <typename PointInT, typename PointOutT> bool
agex::DepthPatchEstimation<PointInT, PointOutT>::initCompute ()
{
  // Indices built from (u, v) last time are ours, not the user's: start afresh.
  if (uv_indices_ && fake_indices_)
    indices_.reset ();
  uv_indices_ = false;
  used_focal_length_ = 0.f;

  if (!input_)
  {
    PCL_ERROR ("[agex::%s::initCompute] No input cloud was given.\n", getClassName ().c_str ());
    return false;
  }
  if (!input_->isOrganized ())
  {
    PCL_ERROR ("[agex::%s::initCompute] The input cloud is not organized (height %u); "
               "depth patches need the pixel grid of a depth frame.\n", getClassName ().c_str (), input_->height);
    return false;
  }
  if (patch_size_ < 1 || patch_size_ > kMaxPatchSize || !(patch_extent_ > 0.f) || !std::isfinite (patch_extent_) ||
      !(clamp_depth_ > 0.f) || !std::isfinite (clamp_depth_) || !(focal_length_ >= 0.f) ||
      !std::isfinite (focal_length_))
  {
    PCL_ERROR ("[agex::%s::initCompute] Invalid parameters: patch size %d (1..%d), extent %g (> 0), "
               "clamp %g (> 0), focal length %g (>= 0, 0 = estimate).\n", getClassName ().c_str (), patch_size_,
               kMaxPatchSize, patch_extent_, clamp_depth_, focal_length_);
    return false;
  }

  const int width = static_cast<int> (input_->width), height = static_cast<int> (input_->height);
  if (interest_points_ && (fake_indices_ || !indices_))
  {
    // No indices were given: the interest points' pixels are the points. Built here
    // rather than after PCLBase::initCompute, which would first list every pixel.
    pcl::IndicesPtr from_uv (new pcl::Indices);
    from_uv->reserve (interest_points_->size ());
    for (std::size_t i = 0; i < interest_points_->size (); ++i)
    {
      const agex::InterestPoint &ip = (*interest_points_)[i];
      if (ip.u < 0 || ip.u >= width || ip.v < 0 || ip.v >= height)
      {
        PCL_ERROR ("[agex::%s::initCompute] Interest point %zu is at pixel (%d, %d), outside the %dx%d cloud.\n",
                   getClassName ().c_str (), i, ip.u, ip.v, width, height);
        return false;
      }
      from_uv->push_back (ip.v * width + ip.u);
    }
    indices_ = from_uv;
    fake_indices_ = true;  // not the user's: setIndices () still takes over
    uv_indices_ = true;
  }
  else
  {
    pcl::PCLBase<PointInT>::initCompute ();  // every pixel when no indices were given
    if (interest_points_ && interest_points_->size () != indices_->size ())
    {
      PCL_ERROR ("[agex::%s::initCompute] %zu interest points for %zu indices; they are matched by order.\n",
                 getClassName ().c_str (), interest_points_->size (), indices_->size ());
      return false;
    }
  }

  bool any_finite = false;
  for (const auto index : *indices_)
  {
    if (index < 0 || static_cast<std::size_t> (index) >= input_->size ())
    {
      PCL_ERROR ("[agex::%s::initCompute] Index %d is outside the %zu-point cloud.\n", getClassName ().c_str (),
                 index, input_->size ());
      return false;
    }
    const float z = (*input_)[index].z;
    any_finite = any_finite || (std::isfinite (z) && z > 0.f);
  }

  // Only points with a finite depth need a focal length; an all-NaN frame needs none.
  if (focal_length_ > 0.f)
    used_focal_length_ = focal_length_;
  else if (any_finite)
  {
    used_focal_length_ = estimateFocalLength (*input_);
    if (!(used_focal_length_ > 0.f))
    {
      PCL_ERROR ("[agex::%s::initCompute] Cannot estimate the focal length from the input cloud "
                 "(too few finite points, or not a pinhole image); call setFocalLength.\n",
                 getClassName ().c_str ());
      return false;
    }
  }

  const int n = patch_size_;
  cell_offsets_.resize (n);
  for (int k = 0; k < n; ++k)
    cell_offsets_[k] = static_cast<float> (k) - 0.5f * static_cast<float> (n - 1);
  return true;
}

template <typename PointInT, typename PointOutT> void
agex::DepthPatchEstimation<PointInT, PointOutT>::computePatch (int index, const agex::InterestPoint *ip,
                                                               PointOutT &out) const
{
  const int n = patch_size_;
  const int cells = n * n;
  const float clamp = clamp_depth_, background = clamp_depth_;
  out.size = n;
  out.metres_per_cell = patch_extent_ / static_cast<float> (n);
  out.orientation[0] = out.orientation[1] = out.orientation[2] = 0.f;
  std::fill (out.patch + cells, out.patch + agex::DepthPatch::kMaxCells, 0.f);

  const PointInT &centre = (*input_)[index];
  const float z0 = centre.z;
  if (!std::isfinite (z0) || !(z0 > 0.f) || !std::isfinite (centre.x) || !std::isfinite (centre.y))
  {
    std::fill (out.patch, out.patch + cells, background);
    return;
  }

  // d: image direction of the orientation (patch +row); e = (d.y, -d.x) (patch +col).
  float dx = 0.f, dy = 1.f;
  if (ip)
  {
    const float ox = ip->orientation[0], oy = ip->orientation[1], oz = ip->orientation[2];
    const float gx = ox - oz * centre.x / z0, gy = oy - oz * centre.y / z0;
    const float g = std::sqrt (gx * gx + gy * gy), o = std::sqrt (ox * ox + oy * oy + oz * oz);
    if (std::isfinite (g) && std::isfinite (o) && o > 0.f && g >= 1e-3f * o)
    {
      dx = gx / g;
      dy = gy / g;
      out.orientation[0] = ox;
      out.orientation[1] = oy;
      out.orientation[2] = oz;
    }
  }
  const float pixels_per_cell = used_focal_length_ * out.metres_per_cell / z0;
  const float col_u = pixels_per_cell * dy, col_v = -pixels_per_cell * dx;  // one cell along +col
  const float row_u = pixels_per_cell * dx, row_v = pixels_per_cell * dy;   // one cell along +row

  const int width = static_cast<int> (input_->width);
  const float fwidth = static_cast<float> (input_->width), fheight = static_cast<float> (input_->height);
  // Pixel k covers [k - 0.5, k + 0.5); with +0.5 the nearest pixel is the truncation.
  const float u0 = static_cast<float> (index % width) + 0.5f;
  const float v0 = static_cast<float> (index / width) + 0.5f;
  const float *offsets = cell_offsets_.data ();
  const PointInT *points = input_->points.data ();
  float *value = out.patch;
  for (int row = 0; row < n; ++row)
  {
    const float base_u = u0 + offsets[row] * row_u, base_v = v0 + offsets[row] * row_v;
    for (int col = 0; col < n; ++col, ++value)
    {
      const float pu = base_u + offsets[col] * col_u, pv = base_v + offsets[col] * col_v;
      // Written so that NaN coordinates (never expected) also count as outside.
      if (!(pu >= 0.f && pu < fwidth && pv >= 0.f && pv < fheight))
      {
        *value = background;
        continue;
      }
      const float z = points[static_cast<int> (pv) * width + static_cast<int> (pu)].z;
      *value = std::isfinite (z) ? std::min (clamp, std::max (-clamp, z - z0)) : background;
    }
  }
}

template <typename PointInT, typename PointOutT> void
agex::DepthPatchEstimation<PointInT, PointOutT>::computeFeature (PointCloudOut &output)
{
  const bool with_orientations = static_cast<bool> (interest_points_);
  for (std::size_t i = 0; i < indices_->size (); ++i)
    computePatch ((*indices_)[i], with_orientations ? &(*interest_points_)[i] : nullptr, output[i]);
  // Every cell is finite (background instead of NaN), whatever the input.
  output.is_dense = true;
}

#define PCL_INSTANTIATE_DepthPatchEstimation(IN, OUT) \
  template class PCL_EXPORTS agex::DepthPatchEstimation<IN, OUT>;
