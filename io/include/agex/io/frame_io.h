#pragma once
// Frame input shared by every app: organized PCD files, 8/16-bit depth PNGs and
// raw little-endian uint16 (.u16) depth, all turned into an organized
// pcl::PointCloud<pcl::PointXYZ> in metres with NaN for invalid pixels.

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <opencv2/core.hpp>

#include <cstdint>
#include <stdexcept>
#include <string>

namespace agex
{
/** Pinhole intrinsics in pixels. Defaults: the Kinect values (../shared/README.md). */
struct CameraIntrinsics
{
  double fx = 525.0;
  double fy = 525.0;
  double cx = 319.5;
  double cy = 239.5;
};

/** What an intrinsic or depth scale is, for intrinsicProblem. */
enum class IntrinsicKind
{
  kFocalLength,     ///< fx, fy: kMinFocalLength to kMaxFocalLength pixels (agex/common/focal_length.h)
  kPrincipalPoint,  ///< cx, cy: finite as a float
  kDepthScale       ///< metres per depth unit: positive and finite as a float
};

/** \brief What is wrong with value as an intrinsic or depth scale of that kind, worded to
  * follow its name ("must be ...; got ..."); "" when nothing is. The one check of the apps'
  * flags, the Python module and depthImageToCloud. Points are floats: a value finite only as
  * a double would give infinite points, or none without a word. */
std::string intrinsicProblem (IntrinsicKind kind, double value);

/** \brief Checks fx, fy, cx and cy with intrinsicProblem.
  * \throws FrameError naming the first that is wrong ("fx must be ...") */
void checkIntrinsics (const CameraIntrinsics &intrinsics);

/** How to interpret a depth image. */
struct FrameOptions
{
  CameraIntrinsics intrinsics;
  /** Metres per depth unit; 0 picks the format's default: 0.016 for 8-bit PNG
    * (the Bonn data's documented scale), 0.001 (millimetres) for 16-bit PNG and .u16. */
  double depth_scale = 0.0;
  /** Image size of a raw .u16 file (it has no header). */
  int width = 640;
  int height = 480;
  /** The image size `intrinsics` are stated for; the defaults are the Kinect's at 640x480.
    * A depth image (PNG, .u16) of another size is refused with a FrameError naming both sizes
    * rather than back-projected with the intrinsics of another image size (a 320x240 frame
    * with 640x480 intrinsics gives a scene of the wrong shape without a word). 0 x 0: the
    * intrinsics are meant for whatever size is loaded (the apps set this when --fx, --fy,
    * --cx or --cy is given). PCD frames carry their points and ignore the intrinsics. */
  int intrinsics_width = 640;
  int intrinsics_height = 480;
};

/** The largest frame loadFrame reads, in pixels (16.7 M, e.g. 4096 x 4096; depth sensors
  * give at most a few million). A file claiming more is refused before anything of its
  * size is allocated, so that a damaged header cannot exhaust memory. */
constexpr std::size_t kMaxFramePixels = std::size_t (1) << 24;

/** An input problem: the message names the file and what is wrong with it. */
class FrameError : public std::runtime_error
{
public:
  using std::runtime_error::runtime_error;
};

/** \brief Refuses a frame larger than kMaxFramePixels before anything of its size is allocated.
  * \throws FrameError naming the file and the claimed size */
void checkFrameSize (const std::string &path, std::uint64_t width, std::uint64_t height);

/** \brief A PNG's size from its IHDR chunk (the first 24 bytes of the file), so that it can
  * be checked before decoding. \return false if head is not the start of a PNG */
bool pngHeaderSize (const unsigned char *head, std::size_t length, std::uint64_t &width, std::uint64_t &height);

/** A loaded frame. */
struct Frame
{
  std::string path;
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud;  ///< organized, metres, NaN = invalid
  CameraIntrinsics intrinsics;                ///< used to back-project (unset for PCD)
  double depth_scale = 0.0;                   ///< metres per unit (0 for PCD)
  bool from_depth_image = false;
};

/** Default metres-per-unit for a depth image of the given OpenCV depth (CV_8U, CV_16U). */
double defaultDepthScale (int cv_depth);

/** \brief Back-projects a single-channel CV_8U, CV_16U or CV_32F depth image (depth =
  * value x depth_scale metres); 0 is invalid, and so are a float image's NaN, infinite and
  * negative values. Any row step is read as it is (no copy of the image).
  * Points whose coordinates do not fit a float are invalid (NaN).
  * \throws FrameError on an unsupported image type, or a depth scale or intrinsics that
  *         intrinsicProblem finds wrong */
void
depthImageToCloud (const cv::Mat &depth, const CameraIntrinsics &intrinsics,
                   double depth_scale, pcl::PointCloud<pcl::PointXYZ> &cloud);

/** \brief Loads a frame by extension: .pcd (organized, any point type with x, y, z),
  * .png (8 or 16-bit single channel depth) or .u16 (raw little-endian uint16).
  * Only regular files are opened (a FIFO would block forever).
  * \throws FrameError naming the file and the problem (missing, not a regular file, truncated,
  *         wrong size, unorganized, not a depth image, larger than kMaxFramePixels, intrinsics
  *         stated for another image size, a principal point outside the image, ...) */
Frame loadFrame (const std::string &path, const FrameOptions &options = FrameOptions ());

/** A crop of an organized frame followed by an isotropic resampling, e.g. the
  * 144x176 portrait view of a 640x480 frame. */
struct FrameView
{
  int x = 0, y = 0, width = 0, height = 0;  ///< crop in source pixels
  double scale = 1.0;                        ///< output pixels per source pixel
  int outputWidth () const;
  int outputHeight () const;
  /** Source pixel sampled for output pixel (u, v) (nearest, pixel centres). */
  cv::Point sourcePixel (int u, int v) const;
  /** Continuous source pixel coordinate to output coordinate. */
  cv::Point2f toView (const cv::Point2f &source) const;
  /** The intrinsics of the view of a frame with intrinsics `source`. */
  CameraIntrinsics intrinsics (const CameraIntrinsics &source) const;
};

/** The view the Bonn source worked on: crop x=140, y=20, 360x440, scaled by 0.4 (144x176). */
FrameView bonnPortraitView ();

/** \brief Resamples an organized cloud to a view. Each output point is a copy of
  * the nearest source point, never a blend, so no mixed depths are invented.
  * \throws FrameError if the crop does not fit inside the cloud */
void applyView (const pcl::PointCloud<pcl::PointXYZ> &input, const FrameView &view,
                pcl::PointCloud<pcl::PointXYZ> &output);
}  // namespace agex
