#include <agex/common/focal_length.h>
#include <agex/io/frame_io.h>
#include <agex/io/image_header.h>
#include <agex/io/input_file.h>
#include <agex/io/pcd_reader.h>

#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <tuple>

namespace fs = std::filesystem;

namespace agex
{
namespace
{
std::string
lowerExtension (const std::string &path)
{
  std::string ext = fs::path (path).extension ().string ();
  std::transform (ext.begin (), ext.end (), ext.begin (), [] (unsigned char c) { return std::tolower (c); });
  return ext;
}

[[noreturn]] void
fail (const std::string &path, const std::string &problem)
{
  throw FrameError (path + ": " + problem);
}

/** A depth PNG, checked by its content (whatever its name) before it is decoded. */
cv::Mat
readDepthPng (const std::string &path)
{
  std::error_code ec;
  if (fs::file_size (path, ec) == 0 && !ec)
    fail (path, "cannot decode PNG (empty file)");
  ImageHeader header;
  const std::vector<unsigned char> bytes = readImageBytes (path, header);
  if (header.format != "PNG")
    fail (path, "is a " + header.format + " image; depth frames are PNG");
  const cv::Mat depth = decodeImageBytes (path, bytes, cv::IMREAD_UNCHANGED);
  if (depth.empty ())
    fail (path, "cannot decode PNG (truncated or not a PNG)");
  return depth;
}

/** agex stages read x, y, z as single floats from any organized cloud. */
void
checkXyzFields (const std::string &path, const pcl::PCLPointCloud2 &cloud)
{
  for (const char *name : {"x", "y", "z"})
  {
    const auto field = std::find_if (cloud.fields.begin (), cloud.fields.end (),
                                     [&] (const pcl::PCLPointField &f) { return f.name == name; });
    if (field == cloud.fields.end ())
      fail (path, std::string ("PCD has no '") + name + "' field; agex needs x, y, z");
    if (field->datatype != pcl::PCLPointField::FLOAT32 || field->count != 1)
      fail (path, std::string ("PCD field '") + name + "' is not a single 4-byte float (TYPE F, SIZE 4, COUNT 1)");
  }
}

Frame
loadPCD (const std::string &path)
{
  const pcl::PCLPointCloud2 blob = readPcd (path);
  checkXyzFields (path, blob);
  if (blob.height <= 1)
    fail (path, "PCD cloud is not organized (height " + std::to_string (blob.height) +
                    "); agex stages need an organized depth frame");
  if (blob.width < 1)
    fail (path, "PCD cloud has no points (width 0)");

  Frame frame;
  frame.path = path;
  frame.cloud.reset (new pcl::PointCloud<pcl::PointXYZ>);
  pcl::fromPCLPointCloud2 (blob, *frame.cloud);
  // PCL marks some invalid points as (0,0,0); agex uses NaN for invalid everywhere.
  for (auto &p : frame.cloud->points)
    if (!std::isfinite (p.x) || !std::isfinite (p.y) || !std::isfinite (p.z) || p.z <= 0.f)
      p.x = p.y = p.z = std::numeric_limits<float>::quiet_NaN ();
  frame.cloud->is_dense = false;
  return frame;
}

cv::Mat
readRawU16 (const std::string &path, int width, int height)
{
  if (width <= 0 || height <= 0)
    fail (path, "a .u16 frame needs a positive --width and --height");
  checkFrameSize (path, static_cast<std::uint64_t> (width), static_cast<std::uint64_t> (height));
  std::ifstream in (path, std::ios::binary | std::ios::ate);
  if (!in)
    fail (path, "cannot open file");
  const std::streamoff size = in.tellg ();
  const std::streamoff expected = static_cast<std::streamoff> (width) * height * 2;
  if (size != expected)
    fail (path, "has " + std::to_string (size) + " bytes, expected " + std::to_string (expected) +
                    " for a " + std::to_string (width) + "x" + std::to_string (height) +
                    " uint16 frame (check --width/--height)");
  cv::Mat depth (height, width, CV_16UC1);
  in.seekg (0);
  // Raw frames are little-endian, as is every platform agex targets.
  static_assert (sizeof (std::uint16_t) == 2, "uint16 must be 2 bytes");
  if (!in.read (reinterpret_cast<char *> (depth.data), expected))
    fail (path, "read error");
  return depth;
}
}  // namespace

bool
pngHeaderSize (const unsigned char *head, std::size_t length, std::uint64_t &width, std::uint64_t &height)
{
  static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (length < 24 || !std::equal (signature, signature + 8, head) || !std::equal (head + 12, head + 16, "IHDR"))
    return false;
  auto big_endian = [] (const unsigned char *b) {
    return (std::uint64_t (b[0]) << 24) | (std::uint64_t (b[1]) << 16) | (std::uint64_t (b[2]) << 8) | b[3];
  };
  width = big_endian (head + 16);
  height = big_endian (head + 20);
  return true;
}

void
checkFrameSize (const std::string &path, std::uint64_t width, std::uint64_t height)
{
  if (width > kMaxFramePixels || height > kMaxFramePixels || width * height > kMaxFramePixels)
    fail (path, "claims a " + std::to_string (width) + "x" + std::to_string (height) +
                    " frame, more than the " + std::to_string (kMaxFramePixels) + " pixels agex reads");
}

double
defaultDepthScale (int cv_depth)
{
  return cv_depth == CV_8U ? 0.016 : 0.001;
}

std::string
intrinsicProblem (IntrinsicKind kind, double value)
{
  const double float_max = std::numeric_limits<float>::max ();
  std::ostringstream text;
  switch (kind)
  {
  case IntrinsicKind::kFocalLength:
    if (saneFocalLength (value))
      return "";
    text << "must be a focal length of " << kMinFocalLength << " to " << kMaxFocalLength << " pixels";
    break;
  case IntrinsicKind::kPrincipalPoint:
    if (std::abs (value) <= float_max)
      return "";
    text << "must be a number of pixels finite as a float (at most " << float_max << " in size)";
    break;
  case IntrinsicKind::kDepthScale:
    if (value > 0.0 && value <= float_max)
      return "";
    text << "must be a positive number of metres per depth unit, finite as a float";
    break;
  }
  text << "; got " << value;
  return text.str ();
}

void
checkIntrinsics (const CameraIntrinsics &k)
{
  for (const auto &[name, value, kind] :
       {std::make_tuple ("fx", k.fx, IntrinsicKind::kFocalLength), std::make_tuple ("fy", k.fy, IntrinsicKind::kFocalLength),
        std::make_tuple ("cx", k.cx, IntrinsicKind::kPrincipalPoint),
        std::make_tuple ("cy", k.cy, IntrinsicKind::kPrincipalPoint)})
  {
    const std::string problem = intrinsicProblem (kind, value);
    if (!problem.empty ())
      throw FrameError (std::string (name) + " " + problem);
  }
}

void
depthImageToCloud (const cv::Mat &depth, const CameraIntrinsics &intrinsics, double depth_scale,
                   pcl::PointCloud<pcl::PointXYZ> &cloud)
{
  const int type = depth.depth ();
  if (depth.empty () || depth.channels () != 1 || (type != CV_8U && type != CV_16U && type != CV_32F))
    throw FrameError ("depth image must be a non-empty single-channel 8 or 16-bit or 32-bit float image");
  const std::string scale_problem = intrinsicProblem (IntrinsicKind::kDepthScale, depth_scale);
  if (!scale_problem.empty ())
    throw FrameError ("depth scale " + scale_problem);
  checkIntrinsics (intrinsics);

  cloud.width = static_cast<std::uint32_t> (depth.cols);
  cloud.height = static_cast<std::uint32_t> (depth.rows);
  cloud.is_dense = false;
  cloud.resize (cloud.width * cloud.height);
  const float nan = std::numeric_limits<float>::quiet_NaN ();
  const double float_max = std::numeric_limits<float>::max ();
  const double inv_fx = 1.0 / intrinsics.fx, inv_fy = 1.0 / intrinsics.fy;
  for (int v = 0; v < depth.rows; ++v)
    for (int u = 0; u < depth.cols; ++u)
    {
      // 0 is invalid; so are a float image's NaN, infinite and negative depths.
      const double raw = type == CV_8U    ? depth.at<std::uint8_t> (v, u)
                         : type == CV_16U ? depth.at<std::uint16_t> (v, u)
                                          : static_cast<double> (depth.at<float> (v, u));
      pcl::PointXYZ &p = cloud (u, v);
      const double z = raw * depth_scale;
      // A point is floats: one beyond their range (a float image's 3e38 m far off-centre) is no point.
      const double x = (u - intrinsics.cx) * z * inv_fx, y = (v - intrinsics.cy) * z * inv_fy;
      if (!(raw > 0.0) || !(z <= float_max && std::abs (x) <= float_max && std::abs (y) <= float_max))
      {
        p.x = p.y = p.z = nan;
        continue;
      }
      p.x = static_cast<float> (x);
      p.y = static_cast<float> (y);
      p.z = static_cast<float> (z);
    }
}

namespace
{
/** The intrinsics must be stated for this image size, with the principal point inside it. */
void
checkImageIntrinsics (const std::string &path, const cv::Mat &depth, const FrameOptions &options)
{
  const CameraIntrinsics &k = options.intrinsics;
  const int w = depth.cols, h = depth.rows;
  if ((options.intrinsics_width > 0 || options.intrinsics_height > 0) &&
      (w != options.intrinsics_width || h != options.intrinsics_height))
  {
    std::ostringstream text;
    text << "a " << w << "x" << h << " depth image, but the intrinsics (fx " << k.fx << ", fy " << k.fy << ", cx "
         << k.cx << ", cy " << k.cy << ") are stated for " << options.intrinsics_width << "x"
         << options.intrinsics_height << "; give this camera's --fx, --fy, --cx and --cy";
    // The same camera binned or upsampled keeps its aspect ratio: say what its values would be.
    if (options.intrinsics_width > 0 && options.intrinsics_height > 0 &&
        std::int64_t (w) * options.intrinsics_height == std::int64_t (h) * options.intrinsics_width)
    {
      const double s = static_cast<double> (w) / options.intrinsics_width;
      text << " (the same camera at " << w << "x" << h << ": --fx " << k.fx * s << " --fy " << k.fy * s << " --cx "
           << (k.cx + 0.5) * s - 0.5 << " --cy " << (k.cy + 0.5) * s - 0.5 << ")";
    }
    fail (path, text.str ());
  }
  // Pixel centres run from 0 to w - 1; the image covers -0.5 to w - 0.5.
  if (!(k.cx >= -0.5 && k.cx <= w - 0.5) || !(k.cy >= -0.5 && k.cy <= h - 0.5))
  {
    std::ostringstream text;
    text << "the principal point (cx " << k.cx << ", cy " << k.cy << ") lies outside the " << w << "x" << h
         << " image; check --cx and --cy";
    fail (path, text.str ());
  }
}
}  // namespace

Frame
loadFrame (const std::string &path, const FrameOptions &options)
{
  std::error_code ec;
  if (!fs::exists (path, ec))
    fail (path, "no such file");
  if (fs::is_directory (path, ec))
    fail (path, "is a directory, expected a frame file");
  // Before anything opens it: a FIFO would block until some other process writes to it.
  const std::string problem = notARegularFile (path);
  if (!problem.empty ())
    fail (path, problem + "; frames are read from regular files only");

  const std::string ext = lowerExtension (path);
  if (ext == ".pcd")
    return loadPCD (path);

  cv::Mat depth;
  if (ext == ".png")
  {
    depth = readDepthPng (path);
    if (depth.channels () != 1)
      fail (path, "is a " + std::to_string (depth.channels ()) +
                      "-channel image; a depth frame must be single-channel");
    if (depth.depth () != CV_8U && depth.depth () != CV_16U)
      fail (path, "depth PNG must be 8 or 16-bit");
  }
  else if (ext == ".u16")
    depth = readRawU16 (path, options.width, options.height);
  else
    fail (path, "unknown frame format '" + ext + "' (expected .pcd, .png or .u16)");
  // Like an organized PCD: pixels need neighbours above or below for any stage to work.
  if (depth.rows < 2 || depth.cols < 2)
    fail (path, "a " + std::to_string (depth.cols) + "x" + std::to_string (depth.rows) +
                    " image; a depth frame needs at least 2 rows and 2 columns");

  checkImageIntrinsics (path, depth, options);
  if (!(options.depth_scale >= 0.0) || !std::isfinite (options.depth_scale))
    fail (path, "the depth scale must be a positive number of metres per unit (or 0 for the format's default)");

  Frame frame;
  frame.path = path;
  frame.from_depth_image = true;
  frame.intrinsics = options.intrinsics;
  frame.depth_scale = options.depth_scale > 0.0 ? options.depth_scale : defaultDepthScale (depth.depth ());
  frame.cloud.reset (new pcl::PointCloud<pcl::PointXYZ>);
  try
  {
    depthImageToCloud (depth, frame.intrinsics, frame.depth_scale, *frame.cloud);
  }
  catch (const FrameError &e)
  {
    fail (path, e.what ());
  }
  return frame;
}

int
FrameView::outputWidth () const
{
  return static_cast<int> (std::floor (width * scale + 1e-9));
}

int
FrameView::outputHeight () const
{
  return static_cast<int> (std::floor (height * scale + 1e-9));
}

cv::Point
FrameView::sourcePixel (int u, int v) const
{
  const int su = x + std::min (width - 1, static_cast<int> (std::floor ((u + 0.5) / scale)));
  const int sv = y + std::min (height - 1, static_cast<int> (std::floor ((v + 0.5) / scale)));
  return {su, sv};
}

cv::Point2f
FrameView::toView (const cv::Point2f &source) const
{
  return {static_cast<float> ((source.x - x + 0.5) * scale - 0.5),
          static_cast<float> ((source.y - y + 0.5) * scale - 0.5)};
}

CameraIntrinsics
FrameView::intrinsics (const CameraIntrinsics &source) const
{
  CameraIntrinsics k = source;
  k.fx *= scale;
  k.fy *= scale;
  k.cx = scale * (source.cx - x + 0.5) - 0.5;  // as toView
  k.cy = scale * (source.cy - y + 0.5) - 0.5;
  return k;
}

FrameView
bonnPortraitView ()
{
  FrameView view;
  view.x = 140;
  view.y = 20;
  view.width = 360;
  view.height = 440;
  view.scale = 0.4;
  return view;
}

void
applyView (const pcl::PointCloud<pcl::PointXYZ> &input, const FrameView &view,
           pcl::PointCloud<pcl::PointXYZ> &output)
{
  if (!input.isOrganized ())
    throw FrameError ("a view needs an organized cloud");
  if (view.x < 0 || view.y < 0 || view.width <= 0 || view.height <= 0 || !(view.scale > 0.0) ||
      view.x + view.width > static_cast<int> (input.width) ||
      view.y + view.height > static_cast<int> (input.height) || view.outputWidth () < 1 ||
      view.outputHeight () < 1)
    throw FrameError ("view crop " + std::to_string (view.width) + "x" + std::to_string (view.height) + "+" +
                      std::to_string (view.x) + "+" + std::to_string (view.y) + " does not fit a " +
                      std::to_string (input.width) + "x" + std::to_string (input.height) + " frame");
  const int ow = view.outputWidth (), oh = view.outputHeight ();
  pcl::PointCloud<pcl::PointXYZ> result (ow, oh);
  for (int v = 0; v < oh; ++v)
    for (int u = 0; u < ow; ++u)
    {
      const cv::Point s = view.sourcePixel (u, v);
      result (u, v) = input (s.x, s.y);
    }
  result.is_dense = false;
  result.header = input.header;
  output = std::move (result);
}
}  // namespace agex
