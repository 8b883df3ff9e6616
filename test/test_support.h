#pragma once
// Helpers shared by the agex tests: where the shared data lives, synthetic
// organized clouds (pinhole rasterisation of analytic figures), temporary
// directories and bitwise comparisons.

#include <agex/common/point_types.h>

#include <pcl/console/print.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#ifndef AGEX_SHARED_DATA_DIR
#define AGEX_SHARED_DATA_DIR "../shared/data"
#endif

namespace agex_test
{
namespace fs = std::filesystem;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

/** A whole file as bytes (empty if it cannot be read). */
inline std::string
readAll (const std::string &path)
{
  std::ifstream in (path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf ();
  return s.str ();
}

/** Replaces a file's contents with bytes. */
inline void
writeAll (const std::string &path, const std::string &bytes)
{
  std::ofstream out (path, std::ios::binary | std::ios::trunc);
  out.write (bytes.data (), static_cast<std::streamsize> (bytes.size ()));
}

/** Keeps the expected PCL_ERROR messages of bad-input tests out of the log. */
class QuietPcl
{
public:
  QuietPcl () : level_ (pcl::console::getVerbosityLevel ()) { pcl::console::setVerbosityLevel (pcl::console::L_ALWAYS); }
  ~QuietPcl () { pcl::console::setVerbosityLevel (level_); }

private:
  pcl::console::VERBOSITY_LEVEL level_;
};

/** Path of a file under the shared data directory (../shared/data by default). */
inline std::string
sharedData (const std::string &relative)
{
  return std::string (AGEX_SHARED_DATA_DIR) + "/" + relative;
}

/** Skips the current test, naming the missing file, if path does not exist. */
#define AGEX_REQUIRE_SHARED_FILE(path, what)                                                   \
  do                                                                                          \
  {                                                                                           \
    if (!std::filesystem::exists (path))                                                      \
      GTEST_SKIP () << (path) << " not found; " << (what) << " is needed for this test";     \
  } while (0)

#define AGEX_REQUIRE_BONN(path) AGEX_REQUIRE_SHARED_FILE (path, "the Bonn dataset (../shared/data/bonn)")

inline float
nanf_ ()
{
  return std::numeric_limits<float>::quiet_NaN ();
}

inline pcl::PointXYZ
nanPoint ()
{
  return pcl::PointXYZ (nanf_ (), nanf_ (), nanf_ ());
}

inline bool
isFinite (const pcl::PointXYZ &p)
{
  return std::isfinite (p.x) && std::isfinite (p.y) && std::isfinite (p.z);
}

/** A pinhole camera and image size. */
struct Camera
{
  double fx = 525.0, fy = 525.0, cx = 159.5, cy = 119.5;
  int width = 320, height = 240;
};

/** An organized cloud of the camera's size, every point NaN. */
inline Cloud::Ptr
nanCloud (int width, int height)
{
  Cloud::Ptr cloud (new Cloud (width, height, nanPoint ()));
  cloud->is_dense = false;
  return cloud;
}

/** The point at depth z on the viewing ray of pixel (u, v). */
inline pcl::PointXYZ
rayPoint (const Camera &cam, int u, int v, double z)
{
  return pcl::PointXYZ (static_cast<float> ((u - cam.cx) * z / cam.fx),
                        static_cast<float> ((v - cam.cy) * z / cam.fy), static_cast<float> (z));
}

/** A planar stick figure on the plane z = depth: a disc with capsule-shaped limbs
  * going out from its centre. Coordinates are metres in the camera's x (right) and
  * y (down). */
struct Figure
{
  struct Limb
  {
    Eigen::Vector2d direction;  ///< unit vector from the centre outwards
    double length;              ///< centre to the end cap's centre
    double half_width;          ///< capsule radius
    Eigen::Vector2d tip (const Eigen::Vector2d &centre) const { return centre + direction * (length + half_width); }
  };
  Eigen::Vector2d centre = Eigen::Vector2d::Zero ();
  double depth = 2.0;
  double disc_radius = 0.08;
  std::vector<Limb> limbs;

  bool contains (const Eigen::Vector2d &p) const
  {
    if ((p - centre).norm () <= disc_radius)
      return true;
    for (const auto &limb : limbs)
    {
      const double t = std::clamp ((p - centre).dot (limb.direction), 0.0, limb.length);
      if ((p - (centre + t * limb.direction)).norm () <= limb.half_width)
        return true;
    }
    return false;
  }

  Eigen::Vector3f tip3D (std::size_t limb) const
  {
    const Eigen::Vector2d t = limbs[limb].tip (centre);
    return Eigen::Vector3f (static_cast<float> (t.x ()), static_cast<float> (t.y ()), static_cast<float> (depth));
  }

  Eigen::Vector3f centre3D () const
  {
    return Eigen::Vector3f (static_cast<float> (centre.x ()), static_cast<float> (centre.y ()),
                            static_cast<float> (depth));
  }
};

/** A star: n limbs evenly spread, the first at first_angle_deg (0 = +x, 90 = +y, down). */
inline Figure
makeStar (const Eigen::Vector2d &centre, double depth, int n, double length, double half_width,
          double disc_radius, double first_angle_deg = -90.0)
{
  Figure f;
  f.centre = centre;
  f.depth = depth;
  f.disc_radius = disc_radius;
  for (int i = 0; i < n; ++i)
  {
    const double a = (first_angle_deg + 360.0 * i / n) * M_PI / 180.0;
    f.limbs.push_back ({Eigen::Vector2d (std::cos (a), std::sin (a)), length, half_width});
  }
  return f;
}

/** Rasterises figures as a pinhole camera sees them: a pixel whose ray hits a
  * figure's plane inside the figure gets that point (the nearest figure wins);
  * every other pixel is NaN (background). */
inline Cloud::Ptr
rasterise (const std::vector<Figure> &figures, const Camera &cam)
{
  Cloud::Ptr cloud = nanCloud (cam.width, cam.height);
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u)
    {
      double best = std::numeric_limits<double>::infinity ();
      for (const auto &f : figures)
      {
        const Eigen::Vector2d p ((u - cam.cx) * f.depth / cam.fx, (v - cam.cy) * f.depth / cam.fy);
        if (f.depth < best && f.contains (p))
        {
          best = f.depth;
          (*cloud) (u, v) = rayPoint (cam, u, v, f.depth);
        }
      }
    }
  return cloud;
}

/** Bit pattern of a float, for bitwise comparisons (0.f vs -0.f, NaN payloads). */
inline std::uint32_t
bits (float f)
{
  std::uint32_t b;
  std::memcpy (&b, &f, sizeof b);
  return b;
}

/** A fresh temporary directory, removed with its contents at scope exit. */
class TempDir
{
public:
  TempDir ()
  {
    std::string tmpl = (fs::temp_directory_path () / "agex-test-XXXXXX").string ();
    if (!::mkdtemp (tmpl.data ()))
      throw std::runtime_error ("cannot create a temporary directory");
    path_ = tmpl;
  }
  ~TempDir ()
  {
    std::error_code ec;
    fs::remove_all (path_, ec);
  }
  TempDir (const TempDir &) = delete;
  TempDir &operator= (const TempDir &) = delete;
  const fs::path &path () const { return path_; }
  std::string file (const std::string &name) const { return (path_ / name).string (); }

private:
  fs::path path_;
};
}  // namespace agex_test
