// Frame input (8/16-bit PNG, raw .u16, organized PCD), the portrait view, atomic
// output files and agex::InterestPoint PCD round trips.

#include "test_support.h"

#include <agex/io/atomic_file.h>
#include <agex/io/frame_io.h>
#include <agex/io/image_header.h>
#include <agex/io/pcd_reader.h>

#include <pcl/io/pcd_io.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <tuple>

#include <sys/resource.h>
#include <sys/stat.h>

namespace
{
using namespace agex_test;


/** Runs f, expecting an agex::FrameError whose message contains every needle. */
template <typename F>
void
expectFrameError (F &&f, const std::vector<std::string> &needles)
{
  try
  {
    f ();
    ADD_FAILURE () << "no agex::FrameError thrown";
  }
  catch (const agex::FrameError &e)
  {
    const std::string message = e.what ();
    for (const auto &needle : needles)
      EXPECT_NE (message.find (needle), std::string::npos) << "'" << needle << "' not in: " << message;
  }
  catch (const std::exception &e)
  {
    ADD_FAILURE () << "expected agex::FrameError, got another exception: " << e.what ();
  }
}

/** Every pixel of depth back-projects as documented: z = value * scale,
  * x = (u - cx) z / fx, y = (v - cy) z / fy, 0 -> NaN. */
void
expectBackProjection (const cv::Mat &depth, const agex::Frame &frame, double scale, const agex::CameraIntrinsics &k)
{
  const Cloud &cloud = *frame.cloud;
  ASSERT_EQ (static_cast<int> (cloud.width), depth.cols);
  ASSERT_EQ (static_cast<int> (cloud.height), depth.rows);
  ASSERT_TRUE (cloud.isOrganized ());
  for (int v = 0; v < depth.rows; ++v)
    for (int u = 0; u < depth.cols; ++u)
    {
      const unsigned raw = depth.depth () == CV_8U ? depth.at<std::uint8_t> (v, u) : depth.at<std::uint16_t> (v, u);
      const pcl::PointXYZ &p = cloud (u, v);
      if (raw == 0)
      {
        EXPECT_TRUE (std::isnan (p.x) && std::isnan (p.y) && std::isnan (p.z)) << u << "," << v;
        continue;
      }
      const double z = raw * scale;
      EXPECT_FLOAT_EQ (p.z, static_cast<float> (z)) << u << "," << v;
      EXPECT_FLOAT_EQ (p.x, static_cast<float> ((u - k.cx) * z / k.fx)) << u << "," << v;
      EXPECT_FLOAT_EQ (p.y, static_cast<float> ((v - k.cy) * z / k.fy)) << u << "," << v;
    }
}

cv::Mat
randomDepth (int rows, int cols, int type, unsigned seed)
{
  cv::Mat depth (rows, cols, type);
  std::mt19937 rng (seed);
  const int max = type == CV_8UC1 ? 255 : 65535;
  std::uniform_int_distribution<int> value (1, max);
  for (int v = 0; v < rows; ++v)
    for (int u = 0; u < cols; ++u)
    {
      const int x = (u + v) % 5 == 0 ? 0 : value (rng);  // some invalid pixels
      if (type == CV_8UC1)
        depth.at<std::uint8_t> (v, u) = static_cast<std::uint8_t> (x);
      else
        depth.at<std::uint16_t> (v, u) = static_cast<std::uint16_t> (x);
    }
  if (type == CV_8UC1)  // the largest value, too
    depth.at<std::uint8_t> (1, 1) = 255;
  else
    depth.at<std::uint16_t> (1, 1) = 65535;
  return depth;
}

// ---------------------------------------------------------------------------
// PNG

TEST (FrameIo, Png8BitRoundTrip)
{
  TempDir dir;
  const cv::Mat depth = randomDepth (6, 8, CV_8UC1, 1);
  const std::string path = dir.file ("depth8.png");
  ASSERT_TRUE (cv::imwrite (path, depth));

  // The default (Kinect) intrinsics are stated for 640x480: for this 8x6 image they are
  // used as they are only when said to be meant for any size.
  agex::FrameOptions any_size;
  any_size.intrinsics_width = any_size.intrinsics_height = 0;
  any_size.intrinsics.cx = any_size.intrinsics.cy = 2.0;
  const agex::Frame frame = agex::loadFrame (path, any_size);
  EXPECT_EQ (frame.path, path);
  EXPECT_TRUE (frame.from_depth_image);
  EXPECT_DOUBLE_EQ (frame.depth_scale, 0.016) << "documented default scale of 8-bit (Bonn) PNGs";
  expectBackProjection (depth, frame, 0.016, any_size.intrinsics);

  agex::FrameOptions options;
  options.intrinsics_width = 8;
  options.intrinsics_height = 6;
  options.intrinsics.fx = 300.0;
  options.intrinsics.fy = 310.0;
  options.intrinsics.cx = 3.5;
  options.intrinsics.cy = 2.25;
  options.depth_scale = 0.02;
  const agex::Frame custom = agex::loadFrame (path, options);
  EXPECT_DOUBLE_EQ (custom.depth_scale, 0.02);
  expectBackProjection (depth, custom, 0.02, options.intrinsics);
}

TEST (FrameIo, Png16BitRoundTrip)
{
  TempDir dir;
  const cv::Mat depth = randomDepth (7, 9, CV_16UC1, 2);
  const std::string path = dir.file ("depth16.PNG");  // extensions are case-insensitive
  ASSERT_TRUE (cv::imwrite (path, depth));
  agex::FrameOptions options;
  options.intrinsics_width = options.intrinsics_height = 0;
  options.intrinsics.cx = 4.0;
  options.intrinsics.cy = 3.0;
  const agex::Frame frame = agex::loadFrame (path, options);
  EXPECT_DOUBLE_EQ (frame.depth_scale, 0.001) << "16-bit PNGs default to millimetres";
  expectBackProjection (depth, frame, 0.001, options.intrinsics);
}

TEST (FrameIo, PngErrors)
{
  TempDir dir;
  // A 3-channel (colour) PNG is not a depth frame.
  const std::string colour = dir.file ("colour.png");
  ASSERT_TRUE (cv::imwrite (colour, cv::Mat (4, 5, CV_8UC3, cv::Scalar (10, 20, 30))));
  expectFrameError ([&] { agex::loadFrame (colour); }, {colour, "3-channel"});

  // A truncated PNG: every cut must give a FrameError, never a crash or a partial frame.
  const std::string good = dir.file ("good.png");
  ASSERT_TRUE (cv::imwrite (good, randomDepth (40, 50, CV_16UC1, 3)));
  const std::string bytes = readAll (good);
  ASSERT_GT (bytes.size (), 100u);
  for (std::size_t keep : {std::size_t (0), std::size_t (8), std::size_t (40), bytes.size () / 2, bytes.size () - 20})
  {
    SCOPED_TRACE ("kept " + std::to_string (keep) + " of " + std::to_string (bytes.size ()) + " bytes");
    const std::string cut = dir.file ("cut.png");
    writeAll (cut, bytes.substr (0, keep));
    expectFrameError ([&] { agex::loadFrame (cut); }, {cut});
  }
  // Not a PNG at all.
  const std::string text = dir.file ("text.png");
  writeAll (text, "this is not an image\n");
  expectFrameError ([&] { agex::loadFrame (text); }, {text});
}

// ---------------------------------------------------------------------------
// Raw .u16

TEST (FrameIo, RawU16CorrectAndWrongSizes)
{
  TempDir dir;
  const int width = 8, height = 6;
  const cv::Mat depth = randomDepth (height, width, CV_16UC1, 4);
  std::string bytes;
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u)
    {
      const std::uint16_t x = depth.at<std::uint16_t> (v, u);
      bytes.push_back (static_cast<char> (x & 0xff));  // little-endian
      bytes.push_back (static_cast<char> (x >> 8));
    }
  const std::string path = dir.file ("frame.u16");
  writeAll (path, bytes);

  agex::FrameOptions options;
  options.width = width;
  options.height = height;
  options.intrinsics_width = width;
  options.intrinsics_height = height;
  options.intrinsics.cx = 3.5;
  options.intrinsics.cy = 2.5;
  const agex::Frame frame = agex::loadFrame (path, options);
  EXPECT_DOUBLE_EQ (frame.depth_scale, 0.001);
  expectBackProjection (depth, frame, 0.001, options.intrinsics);

  // With the default 640x480 size the same file is the wrong size.
  expectFrameError ([&] { agex::loadFrame (path); }, {path, "96 bytes", "614400"});
  // One pixel short, one byte too many.
  const std::string shorter = dir.file ("short.u16");
  writeAll (shorter, bytes.substr (0, bytes.size () - 2));
  expectFrameError ([&] { agex::loadFrame (shorter, options); }, {shorter, "94 bytes", "expected 96"});
  const std::string longer = dir.file ("long.u16");
  writeAll (longer, bytes + "x");
  expectFrameError ([&] { agex::loadFrame (longer, options); }, {longer, "97 bytes"});
  const std::string empty = dir.file ("empty.u16");
  writeAll (empty, "");
  expectFrameError ([&] { agex::loadFrame (empty, options); }, {empty, "0 bytes"});
}

// ---------------------------------------------------------------------------
// PCD

pcl::PointCloud<pcl::PointXYZRGBA>
organizedRgbaCloud ()
{
  pcl::PointCloud<pcl::PointXYZRGBA> cloud (8, 6);
  std::mt19937 rng (5);
  std::uniform_real_distribution<float> uni (-1.f, 1.f);
  for (int v = 0; v < 6; ++v)
    for (int u = 0; u < 8; ++u)
    {
      auto &p = cloud (u, v);
      p.x = uni (rng);
      p.y = uni (rng);
      p.z = 2.f + uni (rng);
      p.r = static_cast<std::uint8_t> (u * 30);
      p.g = static_cast<std::uint8_t> (v * 40);
      p.b = 7;
      p.a = 255;
    }
  cloud (1, 1).x = cloud (1, 1).y = cloud (1, 1).z = nanf_ ();
  cloud (2, 3).x = cloud (2, 3).y = cloud (2, 3).z = 0.f;  // PCL's other "invalid"
  cloud.is_dense = false;
  return cloud;
}

TEST (FrameIo, OrganizedRgbaPcdLoadsAsXyz)
{
  TempDir dir;
  const auto rgba = organizedRgbaCloud ();
  for (int format = 0; format < 3; ++format)
  {
    const std::string path = dir.file ("rgba" + std::to_string (format) + ".pcd");
    SCOPED_TRACE (path);
    if (format == 0)
      ASSERT_EQ (pcl::io::savePCDFileBinary (path, rgba), 0);
    else if (format == 1)
      ASSERT_EQ (pcl::io::savePCDFileBinaryCompressed (path, rgba), 0);
    else
      ASSERT_EQ (pcl::io::savePCDFileASCII (path, rgba), 0);
    const agex::Frame frame = agex::loadFrame (path);
    EXPECT_FALSE (frame.from_depth_image);
    ASSERT_EQ (frame.cloud->width, 8u);
    ASSERT_EQ (frame.cloud->height, 6u);
    for (std::size_t i = 0; i < rgba.size (); ++i)
    {
      const auto &p = (*frame.cloud)[i];
      const bool invalid = i == 1 * 8 + 1 || i == 3 * 8 + 2;
      if (invalid)
      {
        EXPECT_TRUE (std::isnan (p.x) && std::isnan (p.y) && std::isnan (p.z)) << "point " << i << " -> NaN";
        continue;
      }
      if (format < 2)
      {
        EXPECT_EQ (bits (p.x), bits (rgba[i].x)) << i;
        EXPECT_EQ (bits (p.y), bits (rgba[i].y)) << i;
        EXPECT_EQ (bits (p.z), bits (rgba[i].z)) << i;
      }
      else  // ASCII keeps about 8 significant digits
      {
        EXPECT_NEAR (p.x, rgba[i].x, 1e-6f) << i;
        EXPECT_NEAR (p.y, rgba[i].y, 1e-6f) << i;
        EXPECT_NEAR (p.z, rgba[i].z, 1e-6f) << i;
      }
    }
  }
}

TEST (FrameIo, PcdErrors)
{
  TempDir dir;
  // Unorganized.
  pcl::PointCloud<pcl::PointXYZ> flat;
  for (int i = 0; i < 20; ++i)
    flat.push_back (pcl::PointXYZ (0.1f * i, 0.f, 2.f));
  const std::string unorganized = dir.file ("flat.pcd");
  ASSERT_EQ (pcl::io::savePCDFileBinary (unorganized, flat), 0);
  expectFrameError ([&] { agex::loadFrame (unorganized); }, {unorganized, "not organized"});

  // No z field.
  pcl::PointCloud<pcl::PointXY> xy (4, 3);
  const std::string no_z = dir.file ("xy.pcd");
  ASSERT_EQ (pcl::io::savePCDFileBinary (no_z, xy), 0);
  expectFrameError ([&] { agex::loadFrame (no_z); }, {no_z, "'z'"});

  // Truncated: in the data, in the header, and an empty file; binary and compressed.
  const auto rgba = organizedRgbaCloud ();
  for (bool compressed : {false, true})
  {
    const std::string good = dir.file (compressed ? "good_c.pcd" : "good.pcd");
    ASSERT_EQ (compressed ? pcl::io::savePCDFileBinaryCompressed (good, rgba) : pcl::io::savePCDFileBinary (good, rgba), 0);
    const std::string bytes = readAll (good);
    const std::size_t header_end = bytes.find ("DATA");
    ASSERT_NE (header_end, std::string::npos);
    for (std::size_t keep : {std::size_t (0), header_end / 2, header_end + 20, bytes.size () - 40, bytes.size () - 1})
    {
      SCOPED_TRACE (std::string (compressed ? "compressed" : "binary") + ", kept " + std::to_string (keep) + " of " +
                    std::to_string (bytes.size ()) + " bytes");
      const std::string cut = dir.file ("cut.pcd");
      writeAll (cut, bytes.substr (0, keep));
      expectFrameError ([&] { agex::loadFrame (cut); }, {cut});
    }
  }
}

// --- Image headers ----------------------------------------------------------------------

namespace
{
std::string
le16 (unsigned v)
{
  return {static_cast<char> (v & 255), static_cast<char> (v >> 8)};
}

std::string
le32 (std::uint32_t v)
{
  return le16 (v & 0xFFFF) + le16 (v >> 16);
}

/** A classic little-endian TIFF of w x h, 1 bit, one strip of a few bytes (a decompression
  * bomb when large: the decoder allocates what the directory claims). */
std::string
tiff (std::uint32_t w, std::uint32_t h)
{
  std::string t = std::string ("II*\0", 4) + le32 (8);
  const std::vector<std::array<std::uint32_t, 3>> entries = {
    {256, 4, w}, {257, 4, h}, {258, 3, 1}, {259, 3, 1}, {262, 3, 0}, {273, 4, 8 + 2 + 9 * 12 + 4},
    {277, 3, 1}, {278, 4, h}, {279, 4, 16}};
  t += le16 (static_cast<unsigned> (entries.size ()));
  for (const auto &e : entries)
    t += le16 (e[0]) + le16 (e[1]) + le32 (1) + le32 (e[2]);
  return t + le32 (0) + std::string (16, '\0');
}

std::string
encoded (const std::string &ext, const cv::Mat &image)
{
  std::vector<unsigned char> bytes;
  EXPECT_TRUE (cv::imencode (ext, image, bytes)) << ext;
  return std::string (bytes.begin (), bytes.end ());
}

/** The offset of a JPEG's first frame header (SOF0 marker). */
std::size_t
sofAt (const std::string &jpeg)
{
  const std::size_t at = jpeg.find ("\xFF\xC0", 2);
  EXPECT_NE (at, std::string::npos);
  return at;
}

agex::ImageHeader
header (const std::string &bytes, std::string *problem = nullptr)
{
  agex::ImageHeader h;
  const std::string p = agex::parseImageHeader (reinterpret_cast<const unsigned char *> (bytes.data ()), bytes.size (), h);
  if (problem)
    *problem = p;
  else
    EXPECT_EQ (p, "") << h.format;
  return h;
}
}  // namespace

TEST (ImageHeader, SizesOfEveryFormatAsOpenCvWritesThem)
{
  TempDir dir;
  cv::Mat grey (23, 37, CV_8UC1, cv::Scalar (7)), colour (23, 37, CV_8UC3, cv::Scalar (1, 2, 3));
  const std::vector<std::pair<std::string, std::string>> formats = {
    {".png", "PNG"}, {".jpg", "JPEG"}, {".tif", "TIFF"}, {".webp", "WebP"}, {".bmp", "BMP"},
    {".pgm", "PNM"}, {".ppm", "PNM"}, {".pam", "PAM"}, {".pfm", "PFM"}, {".ras", "Sun raster"}};
  for (const auto &[ext, format] : formats)
  {
    SCOPED_TRACE (ext);
    cv::Mat image = ext == ".pgm" ? grey : colour;
    if (ext == ".pfm")
      colour.convertTo (image, CV_32FC3);
    const std::string bytes = encoded (ext, image);
    const agex::ImageHeader h = header (bytes);
    EXPECT_EQ (h.format, format);
    EXPECT_EQ (h.width, 37u);
    EXPECT_EQ (h.height, 23u);
    writeAll (dir.file ("a" + ext), bytes);
    const cv::Mat decoded = agex::readImageFile (dir.file ("a" + ext), cv::IMREAD_UNCHANGED);
    EXPECT_EQ (decoded.size (), cv::Size (37, 23));
  }
  // WebP's lossless (VP8L) and a top-down BMP.
  EXPECT_EQ (header (encoded (".webp", colour), nullptr).width, 37u);
  std::vector<unsigned char> lossless;
  ASSERT_TRUE (cv::imencode (".webp", colour, lossless, {cv::IMWRITE_WEBP_QUALITY, 101}));
  EXPECT_EQ (header (std::string (lossless.begin (), lossless.end ())).height, 23u);
  std::string bmp = encoded (".bmp", colour);
  bmp.replace (22, 4, le32 (static_cast<std::uint32_t> (-23)));
  EXPECT_EQ (header (bmp).height, 23u);
}

TEST (ImageHeader, BombsAreRefusedFromTheHeaderBeforeDecoding)
{
  TempDir dir;
  std::string jpeg = encoded (".jpg", cv::Mat (16, 16, CV_8UC1, cv::Scalar (9)));
  // libjpeg takes the first frame header: one claiming 30000 x 30000, then the 16 x 16 one
  // after the scan, where a check that keeps the last one sees a small image.
  std::string two_sof = jpeg;
  const std::size_t sof = sofAt (two_sof);
  const std::string small_sof = two_sof.substr (sof, 2 + (static_cast<unsigned char> (two_sof[sof + 2]) << 8 |
                                                         static_cast<unsigned char> (two_sof[sof + 3])));
  two_sof[sof + 5] = two_sof[sof + 7] = static_cast<char> (30000 >> 8);
  two_sof[sof + 6] = two_sof[sof + 8] = static_cast<char> (30000 & 255);
  two_sof.insert (two_sof.size () - 2, small_sof);
  // FF 00 right after the start: libjpeg drops it and reads the 30000 x 30000 frame header
  // behind it; a reader taking FF 00 for a segment skips 65504 bytes to a small JPEG there.
  std::string big = two_sof.substr (0, two_sof.size () - 2 - small_sof.size ()) + "\xFF\xD9";
  std::string stuffed = "\xFF\xD8\xFF" + std::string (1, '\0') + big.substr (2);
  stuffed.resize (4 + 0xFFE0, '\0');
  stuffed += jpeg.substr (2);
  // TIFF: libtiff takes the first of two equal tags.
  std::string twice_tiff = std::string ("II*\0", 4) + le32 (8) + le16 (4);
  for (const auto &[tag, value] : std::vector<std::pair<unsigned, std::uint32_t>>{{256, 32767}, {256, 8}, {257, 32767}, {257, 8}})
    twice_tiff += le16 (tag) + le16 (4) + le32 (1) + le32 (value);
  twice_tiff += le32 (0);
  const std::vector<std::tuple<std::string, std::string, std::string>> bombs = {
    {"bomb.tif", tiff (32767, 32767), "claims a 32767x32767"},
    {"bomb_be.tif", std::string ("MM\0*\0\0\0\x08\0\x02\x01\0\0\x04\0\0\0\x01\0\0\x7f\xff\x01\x01\0\x04\0\0\0\x01\0\0\x7f\xff", 34),
     "claims a 32767x32767"},
    {"bomb.webp", "RIFF" + le32 (30) + "WEBPVP8X" + le32 (10) + std::string (4, '\0') + std::string ("\xff\x3f\0\xff\x3f\0", 6),
     "claims a 16384x16384"},
    {"bomb_lossless.webp", "RIFF" + le32 (30) + "WEBPVP8L" + le32 (10) + "\x2f" + le32 (0x0FFFFFFF) + std::string (5, '\0'),
     "claims a 16384x16384"},
    {"bomb.bmp", "BM" + le32 (0) + le32 (0) + le32 (54) + le32 (40) + le32 (30000) + le32 (static_cast<std::uint32_t> (-30000)) +
                   le16 (1) + le16 (24) + std::string (24, '\0'),
     "claims a 30000x30000"},
    {"bomb.pgm", "P5\n# a comment\n30000 30000\n255\n", "claims a 30000x30000"},
    {"bomb.pam", "P7\nWIDTH 30000\nHEIGHT 30000\nDEPTH 1\nMAXVAL 255\nTUPLTYPE GRAYSCALE\nENDHDR\n", "claims a 30000x30000"},
    {"bomb.pfm", "Pf\n30000 30000\n-1.0\n", "claims a 30000x30000"},
    {"bomb.ras", std::string ("\x59\xA6\x6A\x95\0\0\x75\x30\0\0\x75\x30\0\0\0\x08", 16) + std::string (16, '\0'),
     "claims a 30000x30000"},
    {"two_sof.jpg", two_sof, "two frame headers (SOF) that disagree: 30000x30000, then 16x16"},
    {"stuffed_zero.jpg", stuffed, "claims a 30000x30000"},
    {"twice.tif", twice_tiff, "gives the image width twice"},
    {"cr.pam", "P7\n#\rWIDTH 30000\rHEIGHT 30000\rDEPTH 1\rMAXVAL 255\rENDHDR\nWIDTH 8\nHEIGHT 6\nENDHDR\n",
     "a carriage return"},
    {"indented.pam", "P7\n WIDTH 30000\nHEIGHT 30000\nDEPTH 1\nMAXVAL 255\nENDHDR\n", "claims a 30000x30000"},
    {"width_twice.pam", "P7\nWIDTH 30000\nWIDTH 8\nHEIGHT 6\nDEPTH 1\nMAXVAL 255\nENDHDR\n", "WIDTH given twice"},
    // OpenCV takes the byte after a number with it: the height is 300000, not a comment (the
    // fuzzer found this; OpenCV then threw past its own pixel limit, which killed the app).
    {"hash.pgm", "P5\n# comment\n30000#300000\n25\n", "claims a 30000x300000"},
    {"cut.jpg", jpeg.substr (0, jpeg.size () - 2), "truncated JPEG"},
    {"j2k.jp2", std::string ("\0\0\0\x0CjP  \r\n\x87\n", 12), "JPEG 2000"},
    {"bigtiff.tif", std::string ("II+\0\x08\0\0\0", 8), "BigTIFF"},
    {"text.png", "hello", "not an image agex reads"},
    {"empty.jpg", "", "empty file"},
  };
  for (const auto &[name, bytes, expect] : bombs)
  {
    SCOPED_TRACE (name);
    const std::string path = dir.file (name);
    writeAll (path, bytes);
    const auto start = std::chrono::steady_clock::now ();
    expectFrameError ([&] { agex::readImageFile (path, cv::IMREAD_UNCHANGED); }, {path, expect});
    EXPECT_LT (std::chrono::duration<double> (std::chrono::steady_clock::now () - start).count (), 0.5);
  }
  // A stray byte before a marker: libjpeg skips it with a warning, and so does the check.
  EXPECT_EQ (header (jpeg.substr (0, 20) + "x" + jpeg.substr (20)).width, 16u);
  // The name does not matter: a TIFF named .png is a TIFF, for frames too.
  writeAll (dir.file ("tiff.png"), tiff (32767, 32767));
  expectFrameError ([&] { agex::loadFrame (dir.file ("tiff.png")); }, {dir.file ("tiff.png"), "claims a 32767x32767"});
  writeAll (dir.file ("small_tiff.png"), encoded (".tif", cv::Mat (8, 8, CV_16UC1, cv::Scalar (1000))));
  expectFrameError ([&] { agex::loadFrame (dir.file ("small_tiff.png")); }, {"is a TIFF image; depth frames are PNG"});
  // A large (sparse) file is refused from its size, before it is read.
  const std::string large = dir.file ("large.jpg");
  writeAll (large, jpeg);
  fs::resize_file (large, agex::kMaxImageFileBytes + 1);
  const auto start = std::chrono::steady_clock::now ();
  expectFrameError ([&] { agex::readImageFile (large, cv::IMREAD_UNCHANGED); }, {large, "bytes, larger than the"});
  EXPECT_LT (std::chrono::duration<double> (std::chrono::steady_clock::now () - start).count (), 0.5);
}

TEST (FrameIo, HugeClaimedSizesAndDamagedFieldsAreRefusedBeforeReading)
{
  TempDir dir;
  const std::string header = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
  // A PCD header claiming 100000 x 100000 points over a few bytes of data (PCL would
  // allocate 120 GB for it), for each storage type.
  for (const char *data : {"ascii", "binary", "binary_compressed"})
  {
    SCOPED_TRACE (data);
    const std::string huge = dir.file ("huge.pcd");
    writeAll (huge, header + "WIDTH 100000\nHEIGHT 100000\nPOINTS 10000000000\nDATA " + data + "\n0 0 1\n");
    expectFrameError ([&] { agex::loadFrame (huge); }, {huge, "100000x100000", "pixels agex reads"});
  }
  // Within the limit, but more points than the file can hold.
  const std::string short_ascii = dir.file ("short.pcd");
  writeAll (short_ascii, header + "WIDTH 1000\nHEIGHT 1000\nPOINTS 1000000\nDATA ascii\n0 0 1\n");
  expectFrameError ([&] { agex::loadFrame (short_ascii); }, {short_ascii, "does not match its header"});
  // Keywords twice, misspelt by a prefix, or with numbers that are not whole (PCL's header
  // parser accepts all three and then corrupts its heap on some); a well-formed header of the
  // same frame loads.
  const std::string body = "WIDTH 2\nHEIGHT 2\nPOINTS 4\nDATA ascii\n0 0 1\n0 0 1\n0 0 1\n0 0 1\n";
  const std::string well_formed = dir.file ("well_formed.pcd");
  writeAll (well_formed, header + body);
  EXPECT_EQ (agex::loadFrame (well_formed).cloud->size (), 4u);
  const std::string twice = dir.file ("twice.pcd");
  writeAll (twice, header + "FIELDS x y z\n" + body);
  expectFrameError ([&] { agex::loadFrame (twice); }, {twice, "more than one FIELDS"});
  const std::string prefixed = dir.file ("prefixed.pcd");
  writeAll (prefixed, "VERSION 0.7\nFIELDS x y z\nSIZEX 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n" + body);
  expectFrameError ([&] { agex::loadFrame (prefixed); }, {prefixed, "damaged"});
  const std::string not_whole = dir.file ("not_whole.pcd");
  writeAll (not_whole, "VERSION 0.7\nFIELDS x y z\nSIZE 4? 4 4\nTYPE F F F\nCOUNT 1 1 1\n" + body);
  expectFrameError ([&] { agex::loadFrame (not_whole); }, {not_whole, "not a whole number"});
  // Fields that do not fit the point (a repeated SIZE line), and no WIDTH line.
  const std::string bad_fields = dir.file ("fields.pcd");
  writeAll (bad_fields, header + "SIZE 4 4 0\nWIDTH 2\nHEIGHT 2\nPOINTS 4\nDATA ascii\n0 0 1\n0 0 1\n0 0 1\n0 0 1\n");
  expectFrameError ([&] { agex::loadFrame (bad_fields); }, {bad_fields});
  const std::string no_width = dir.file ("no_width.pcd");
  writeAll (no_width, header + "HEIGHT 3\nPOINTS 0\nDATA ascii\n");
  expectFrameError ([&] { agex::loadFrame (no_width); }, {no_width});

  // A PNG whose header claims 100000 x 100000 pixels.
  cv::Mat small (4, 4, CV_8UC1, cv::Scalar (100));
  std::vector<unsigned char> png;
  ASSERT_TRUE (cv::imencode (".png", small, png));
  for (int i : {16, 20})  // IHDR width, height (big-endian)
  {
    png[i] = 0x00, png[i + 1] = 0x01, png[i + 2] = 0x86, png[i + 3] = 0xa0;
  }
  const std::string huge_png = dir.file ("huge.png");
  writeAll (huge_png, std::string (png.begin (), png.end ()));
  expectFrameError ([&] { agex::loadFrame (huge_png); }, {huge_png, "100000x100000"});

  // A raw frame said to be that large.
  agex::FrameOptions options;
  options.width = options.height = 100000;
  const std::string raw = dir.file ("huge.u16");
  writeAll (raw, "abcd");
  expectFrameError ([&] { agex::loadFrame (raw, options); }, {raw, "100000x100000"});
}

// ---------------------------------------------------------------------------
// agex::readPcd against PCL's writer and reader, and hostile files

/** PCL's own reader on a file it wrote (the reference for readPcd on good files). */
pcl::PCLPointCloud2
readWithPcl (const std::string &path)
{
  pcl::PCLPointCloud2 blob;
  EXPECT_EQ (pcl::PCDReader ().read (path, blob), 0) << path;
  return blob;
}

void
expectSameCloud (const pcl::PCLPointCloud2 &ours, const pcl::PCLPointCloud2 &pcls)
{
  EXPECT_EQ (ours.width, pcls.width);
  EXPECT_EQ (ours.height, pcls.height);
  EXPECT_EQ (ours.point_step, pcls.point_step);
  EXPECT_EQ (ours.row_step, pcls.row_step);
  EXPECT_EQ (ours.is_dense, pcls.is_dense);
  ASSERT_EQ (ours.fields.size (), pcls.fields.size ());
  for (std::size_t i = 0; i < ours.fields.size (); ++i)
  {
    EXPECT_EQ (ours.fields[i].name, pcls.fields[i].name);
    EXPECT_EQ (ours.fields[i].offset, pcls.fields[i].offset);
    EXPECT_EQ (int (ours.fields[i].datatype), int (pcls.fields[i].datatype));
    EXPECT_EQ (ours.fields[i].count, pcls.fields[i].count);
  }
  EXPECT_TRUE (ours.data == pcls.data) << "data bytes differ";
}

template <typename PointT>
void
expectPcdRoundTrip (const pcl::PointCloud<PointT> &cloud, const TempDir &dir)
{
  for (const char *format : {"ascii", "binary", "binary_compressed"})
  {
    const std::string path = dir.file (std::string (format) + ".pcd");
    SCOPED_TRACE (path);
    const std::string name (format);
    ASSERT_EQ (name == "ascii"    ? pcl::io::savePCDFileASCII (path, cloud)
               : name == "binary" ? pcl::io::savePCDFileBinary (path, cloud)
                                  : pcl::io::savePCDFileBinaryCompressed (path, cloud),
               0);
    const pcl::PCLPointCloud2 blob = agex::readPcd (path);
    expectSameCloud (blob, readWithPcl (path));
    pcl::PointCloud<PointT> back;
    pcl::fromPCLPointCloud2 (blob, back);
    ASSERT_EQ (back.width, cloud.width);
    ASSERT_EQ (back.height, cloud.height);
    for (std::size_t i = 0; i < cloud.size (); ++i)
    {
      // Every value is a multiple of 1/64 below 4: ascii keeps it exactly too.
      EXPECT_EQ (bits (back[i].x), bits (cloud[i].x)) << i;
      EXPECT_EQ (bits (back[i].y), bits (cloud[i].y)) << i;
      EXPECT_EQ (bits (back[i].z), bits (cloud[i].z)) << i;
      if constexpr (std::is_same_v<PointT, pcl::PointXYZRGBA>)
      {
        EXPECT_EQ (back[i].rgba, cloud[i].rgba) << i;
      }
    }
  }
}

template <typename PointT>
pcl::PointCloud<PointT>
exactlyPrintableCloud (int width, int height)
{
  pcl::PointCloud<PointT> cloud (width, height);
  std::mt19937 rng (9);
  std::uniform_int_distribution<int> steps (-255, 255);
  for (auto &p : cloud.points)
  {
    p.x = steps (rng) / 64.f;
    p.y = steps (rng) / 64.f;
    p.z = 2.f + steps (rng) / 128.f;
    if constexpr (std::is_same_v<PointT, pcl::PointXYZRGBA>)
      p.rgba = static_cast<std::uint32_t> (rng ());
  }
  cloud (3, 2).x = cloud (3, 2).y = cloud (3, 2).z = nanf_ ();
  cloud (0, 0).z = nanf_ ();
  cloud.is_dense = false;
  return cloud;
}

TEST (PcdReader, ReadsWhatPclWritesAsPclDoes)
{
  TempDir dir;
  expectPcdRoundTrip (exactlyPrintableCloud<pcl::PointXYZ> (7, 5), dir);
  expectPcdRoundTrip (exactlyPrintableCloud<pcl::PointXYZRGBA> (7, 5), dir);
  // A dense cloud stays dense.
  auto dense = exactlyPrintableCloud<pcl::PointXYZ> (4, 3);
  dense (3, 2).x = dense (3, 2).y = dense (0, 0).z = 1.f;
  dense (3, 2).z = 1.f;
  dense.is_dense = true;
  ASSERT_EQ (pcl::io::savePCDFileBinaryCompressed (dir.file ("dense.pcd"), dense), 0);
  EXPECT_TRUE (agex::readPcd (dir.file ("dense.pcd")).is_dense);
}

TEST (PcdReader, SharedKinectFrameReadsAsPclReadsIt)
{
  const std::string pcd = sharedData ("kinect/five_people.pcd");
  AGEX_REQUIRE_SHARED_FILE (pcd, "the Kinect test data (../shared/data/kinect)");
  expectSameCloud (agex::readPcd (pcd), readWithPcl (pcd));
}

const std::string kXyzHeader = "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                               "WIDTH 2\nHEIGHT 2\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\n";

/** A binary_compressed 2x2 xyz file: the two sizes, then the LZF bytes. */
std::string
compressedPcd (std::uint32_t compressed_size, std::uint32_t uncompressed_size, const std::string &lzf)
{
  std::string sizes (8, '\0');
  std::memcpy (&sizes[0], &compressed_size, 4);
  std::memcpy (&sizes[4], &uncompressed_size, 4);
  return kXyzHeader + "DATA binary_compressed\n" + sizes + lzf;
}

std::string
compressedPcd (const std::string &lzf)
{
  return compressedPcd (static_cast<std::uint32_t> (lzf.size ()), 48, lzf);
}

/** Writes bytes to path and expects readPcd to refuse them with a message holding every needle. */
void
expectPcdRefused (const std::string &path, const std::string &bytes, const std::vector<std::string> &needles)
{
  writeAll (path, bytes);
  expectFrameError ([&] { agex::readPcd (path); }, needles);
}

TEST (PcdReader, HandWrittenLzfBackReferencesDecompress)
{
  TempDir dir;
  // A literal 1.0f, then one long back-reference 4 bytes back copying 44 bytes over itself.
  std::string lzf ("\x03\x00\x00\x80\x3f", 5);
  lzf += std::string ("\xe0\x23\x03", 3);  // (7 << 5) | 0, 7 + 35 + 2 = 44 bytes, distance 3 + 1
  const std::string path = dir.file ("ones.pcd");
  writeAll (path, compressedPcd (lzf));
  pcl::PointCloud<pcl::PointXYZ> cloud;
  pcl::fromPCLPointCloud2 (agex::readPcd (path), cloud);
  ASSERT_EQ (cloud.size (), 4u);
  for (const auto &p : cloud.points)
    EXPECT_TRUE (p.x == 1.f && p.y == 1.f && p.z == 1.f);
}

TEST (PcdReader, HostileCompressedDataIsRefused)
{
  TempDir dir;
  const std::string path = dir.file ("hostile.pcd");
  auto expectRefused = [&] (const std::string &bytes, const std::vector<std::string> &needles) {
    expectPcdRefused (path, bytes, needles);
  };
  const std::string literal48 = std::string (1, '\x1f') + std::string (32, '\x01') + std::string (1, '\x0f') +
                                std::string (16, '\x02');
  writeAll (path, compressedPcd (literal48));
  EXPECT_EQ (agex::readPcd (path).data.size (), 48u);  // the well-formed base of the cases below

  // Truncated: the block claims more bytes than the file holds, or the file ends in the sizes.
  expectRefused (compressedPcd (literal48).substr (0, compressedPcd (literal48).size () - 10),
                 {path, "PCD data does not match its header", "claims 50 bytes, the file holds 40"});
  expectRefused (kXyzHeader + "DATA binary_compressed\n\x10\x00", {path, "no sizes"});
  // A back-reference before the start of the output.
  expectRefused (compressedPcd (std::string ("\x20\x00", 2) + literal48), {path, "before the start of the data"});
  // A literal run past the end of the compressed data.
  expectRefused (compressedPcd (std::string ("\x1f\x01\x02\x03\x04\x05", 6)), {path, "goes past the end"});
  // More output than the header's points: by a literal run and by a back-reference.
  expectRefused (compressedPcd (literal48 + std::string ("\x00\x07", 2)), {path, "more than the 48 bytes"});
  expectRefused (compressedPcd (literal48 + std::string ("\x20\x00", 2)), {path, "more than the 48 bytes"});
  // Less output than the header's points.
  expectRefused (compressedPcd (literal48.substr (0, 33)), {path, "decompresses to 32 bytes", "48"});
  // A back-reference cut off at the end of the data.
  expectRefused (compressedPcd (literal48.substr (0, 33) + std::string ("\xe0", 1)), {path, "cut off"});
  // The uncompressed size is not the points' size; a size no LZF block of its length can give.
  expectRefused (compressedPcd (static_cast<std::uint32_t> (literal48.size ()), 47, literal48),
                 {path, "claims 47 bytes, the header 48"});
  expectRefused (compressedPcd (0, 48, ""), {path, "cannot hold the 48"});
  // A block longer than LZF makes of 48 bytes even as literals (refused before it is read).
  expectRefused (compressedPcd (literal48 + std::string (50, '\x01')), {path, "more than LZF makes of the 48"});
  // A 4096 x 4096 frame (192 MiB of points) from a 2-byte block: refused on the sizes alone.
  std::string sizes (8, '\0');
  const std::uint32_t block = 2, claimed = 4096u * 4096u * 12u;
  std::memcpy (&sizes[0], &block, 4);
  std::memcpy (&sizes[4], &claimed, 4);
  expectRefused ("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 4096\nHEIGHT 4096\nPOINTS 16777216\n"
                 "DATA binary_compressed\n" + sizes + std::string ("\x00\x01", 2),
                 {path, "compressed PCD data of 2 bytes cannot hold the 201326592"});
}

TEST (PcdReader, HostileAsciiAndHeadersAreRefused)
{
  TempDir dir;
  const std::string path = dir.file ("hostile.pcd");
  auto expectRefused = [&] (const std::string &bytes, const std::vector<std::string> &needles) {
    expectPcdRefused (path, bytes, needles);
  };
  const std::string ascii = kXyzHeader + "DATA ascii\n";
  writeAll (path, ascii + "1 2 3\n\n4 5 6\nnan nan nan\n-1.5 +2 3e-2\n");
  pcl::PointCloud<pcl::PointXYZ> cloud;
  pcl::fromPCLPointCloud2 (agex::readPcd (path), cloud);
  EXPECT_EQ (cloud (1, 0).z, 6.f);
  EXPECT_TRUE (std::isnan (cloud (0, 1).x));
  EXPECT_EQ (cloud (1, 1).y, 2.f);
  EXPECT_FLOAT_EQ (cloud (1, 1).z, 0.03f);

  expectRefused (ascii + "10 20 30\n4 5\n10 20 30\n10 20 30\n", {path, "point 2 has 2 values, the header 3"});
  expectRefused (ascii + "1 2 3\n1 2 3 4\n1 2 3\n1 2 3\n", {path, "point 2 has 4 values, the header 3"});
  expectRefused (ascii + "10 20 30\n10 20 30\n10 20 30\n", {path, "ascii data has 3 points, the header 4"});
  expectRefused (ascii + "1 2 3\n1 2 3\n1 2 3\n1 2 3\n1 2 3\n", {path, "more lines than its 4 points"});
  expectRefused (ascii + "1 2 3\n1 2 3\n1 x 3\n1 2 3\n", {path, "point 3: 'x' is not a number of field 'y'"});
  expectRefused (ascii + "1 2 3\n1 2 3\n1 1e39 3\n1 2 3\n", {path, "'1e39' is not a number"});
  // PCL's TYPE letters in either case, and B (bool) of size 1.
  writeAll (path, "FIELDS x y z valid\nSIZE 4 4 4 1\nTYPE f F f B\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n"
                  "1 2 3 1\n4 5 6 0\n");
  const pcl::PCLPointCloud2 with_bool = agex::readPcd (path);
  ASSERT_EQ (with_bool.fields.size (), 4u);
  EXPECT_EQ (with_bool.fields[0].datatype, pcl::PCLPointField::FLOAT32);
  EXPECT_EQ (with_bool.fields[3].datatype, pcl::PCLPointField::BOOL);
  EXPECT_EQ (with_bool.data[12], 1);
  EXPECT_EQ (with_bool.data[13 + 12], 0);
  // Too small for a float is read as PCL reads it, not refused.
  writeAll (path, ascii + "1 2 3\n1 2 3\n1 1e-50 -1e-42\n1 2 3\n");
  pcl::fromPCLPointCloud2 (agex::readPcd (path), cloud);
  EXPECT_EQ (cloud (0, 1).y, 0.f);
  EXPECT_LT (cloud (0, 1).z, 0.f);
  EXPECT_GT (cloud (0, 1).z, -1e-41f);
  const std::string bytes_header = "VERSION 0.7\nFIELDS x y z i\nSIZE 4 4 4 1\nTYPE F F F U\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n";
  writeAll (path, bytes_header + "1 2 3 255\n1 2 3 0\n");
  EXPECT_EQ (agex::readPcd (path).data[12], 255);
  expectRefused (bytes_header + "1 2 3 256\n1 2 3 0\n", {path, "'256' is not a number of field 'i' (TYPE and SIZE U 1)"});
  expectRefused (bytes_header + "1 2 3 -1\n1 2 3 0\n", {path, "'-1' is not a number"});

  // A SIZE its TYPE does not have, a missing COUNT value, POINTS not WIDTH x HEIGHT, an
  // unknown DATA kind, a repeated field, a header without DATA.
  const std::string body = "DATA ascii\n1 2 3\n1 2 3\n1 2 3\n1 2 3\n";
  expectRefused ("FIELDS x y z\nSIZE 4 4 2\nTYPE F F F\nWIDTH 2\nHEIGHT 2\nPOINTS 4\n" + body,
                 {path, "field 'z' has TYPE F and SIZE 2 (damaged SIZE or TYPE line)"});
  expectRefused ("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1\nWIDTH 2\nHEIGHT 2\nPOINTS 4\n" + body,
                 {path, "3 fields but 3 sizes, 3 types and 2 counts"});
  expectRefused ("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 2\nPOINTS 5\n" + body,
                 {path, "POINTS 5 but WIDTH x HEIGHT is 2x2"});
  expectRefused ("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 2\nPOINTS 4\nDATA binary_lzma\n",
                 {path, "DATA line says 'binary_lzma'"});
  expectRefused ("FIELDS x y x\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 2\nPOINTS 4\n" + body,
                 {path, "field 'x' appears twice"});
  expectRefused ("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 2\nPOINTS 4\n", {path, "bad or missing header"});
  expectRefused ("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 100000\nWIDTH 2\nHEIGHT 2\nPOINTS 4\n" + body,
                 {path, "larger than the 65536 bytes"});
  // A header that does not end in the first 64 KiB.
  expectRefused (std::string (70000, '#') + "\n" + kXyzHeader + body, {path, "no DATA line in its first 65536 bytes"});
  // Binary data shorter than the points.
  expectRefused (kXyzHeader + "DATA binary\n" + std::string (47, '\0'), {path, "binary data of 47 bytes, the header 48"});
}

TEST (FrameIo, IntrinsicsOfAnotherImageSizeAreRefused)
{
  TempDir dir;
  // A 320x240 depth image with the defaults (the Kinect's at 640x480): refused, saying what
  // the same camera's intrinsics would be at that size.
  const std::string qvga = dir.file ("qvga.png");
  ASSERT_TRUE (cv::imwrite (qvga, cv::Mat (240, 320, CV_16UC1, cv::Scalar (1500))));
  expectFrameError ([&] { agex::loadFrame (qvga); },
                    {qvga, "a 320x240 depth image", "stated for 640x480", "--fx 262.5 --fy 262.5 --cx 159.5 --cy 119.5"});
  // Another aspect ratio gets no suggestion: only this camera's own values will do.
  const std::string portrait = dir.file ("portrait.u16");
  writeAll (portrait, std::string (144 * 176 * 2, '\x07'));
  agex::FrameOptions options;
  options.width = 144;
  options.height = 176;
  try
  {
    agex::loadFrame (portrait, options);
    ADD_FAILURE () << "a 144x176 frame with 640x480 intrinsics was loaded";
  }
  catch (const agex::FrameError &e)
  {
    EXPECT_NE (std::string (e.what ()).find ("a 144x176 depth image"), std::string::npos) << e.what ();
    EXPECT_EQ (std::string (e.what ()).find ("the same camera"), std::string::npos) << e.what ();
  }
  // Intrinsics for this size (or said to be for any size) are used.
  options.intrinsics = {210.0, 210.0, 71.5, 87.5};
  options.intrinsics_width = 144;
  options.intrinsics_height = 176;
  EXPECT_EQ (agex::loadFrame (portrait, options).cloud->width, 144u);
  options.intrinsics_width = options.intrinsics_height = 0;
  EXPECT_EQ (agex::loadFrame (portrait, options).cloud->height, 176u);
  // A principal point outside the image is an error, whatever the size rule.
  options.intrinsics.cx = 144.0;
  expectFrameError ([&] { agex::loadFrame (portrait, options); },
                    {portrait, "principal point (cx 144, cy 87.5) lies outside the 144x176 image"});
  options.intrinsics.cx = 71.5;
  options.intrinsics.cy = -1.0;
  expectFrameError ([&] { agex::loadFrame (portrait, options); }, {portrait, "principal point"});
  options.intrinsics.cy = std::nan ("");
  expectFrameError ([&] { agex::loadFrame (portrait, options); }, {portrait, "principal point"});
  // The image's edges (pixel centres -0.5 and w - 0.5 away) are still inside.
  options.intrinsics.cx = -0.5;
  options.intrinsics.cy = 175.5;
  EXPECT_NO_THROW (agex::loadFrame (portrait, options));
  // A negative or NaN depth scale is refused, not taken for the default.
  options.depth_scale = -0.001;
  expectFrameError ([&] { agex::loadFrame (portrait, options); }, {portrait, "depth scale"});
  options.depth_scale = std::nan ("");
  expectFrameError ([&] { agex::loadFrame (portrait, options); }, {portrait, "depth scale"});
  // PCD frames carry their points: the intrinsics play no part.
  const std::string pcd = dir.file ("small.pcd");
  Cloud cloud (5, 4, pcl::PointXYZ (0.f, 0.f, 1.f));
  ASSERT_EQ (pcl::io::savePCDFileBinary (pcd, cloud), 0);
  EXPECT_EQ (agex::loadFrame (pcd).cloud->width, 5u);
}

TEST (FrameIo, FifosAndOtherNonRegularFilesAreRefusedWithoutBlocking)
{
  // Opening a FIFO for reading blocks until a writer appears: before the check, each of
  // these calls hung for ever (the test would end in ctest's timeout).
  TempDir dir;
  for (const char *name : {"fifo.u16", "fifo.png", "fifo.pcd"})
  {
    const std::string fifo = dir.file (name);
    ASSERT_EQ (::mkfifo (fifo.c_str (), 0600), 0) << std::strerror (errno);
    expectFrameError ([&] { agex::loadFrame (fifo); }, {fifo, "is a FIFO (named pipe), not a regular file"});
  }
  expectFrameError ([&] { agex::readPcd (dir.file ("fifo.pcd")); }, {"fifo.pcd", "FIFO"});
  // A character device that never ends.
  expectFrameError ([&] { agex::readPcd ("/dev/zero"); }, {"/dev/zero", "is a character device"});
}

TEST (FrameIo, MissingFileDirectoryAndUnknownFormat)
{
  TempDir dir;
  const std::string missing = dir.file ("nope.png");
  expectFrameError ([&] { agex::loadFrame (missing); }, {missing, "no such file"});
  expectFrameError ([&] { agex::loadFrame (dir.path ().string ()); }, {dir.path ().string (), "directory"});
  const std::string odd = dir.file ("frame.jpg");
  writeAll (odd, "x");
  expectFrameError ([&] { agex::loadFrame (odd); }, {odd, ".jpg"});
}

TEST (FrameIo, DepthImageToCloudRejectsBadInput)
{
  Cloud cloud;
  const cv::Mat depth (4, 4, CV_16UC1, cv::Scalar (1000));
  EXPECT_THROW (agex::depthImageToCloud (cv::Mat (), agex::CameraIntrinsics (), 0.001, cloud), agex::FrameError);
  EXPECT_THROW (agex::depthImageToCloud (cv::Mat (4, 4, CV_64FC1), agex::CameraIntrinsics (), 0.001, cloud),
                agex::FrameError);
  EXPECT_THROW (agex::depthImageToCloud (cv::Mat (4, 4, CV_16UC2), agex::CameraIntrinsics (), 0.001, cloud),
                agex::FrameError);
  EXPECT_THROW (agex::depthImageToCloud (depth, agex::CameraIntrinsics (), 0.0, cloud), agex::FrameError);
  EXPECT_THROW (agex::depthImageToCloud (depth, agex::CameraIntrinsics (), std::nan (""), cloud), agex::FrameError);
  agex::CameraIntrinsics zero_f;
  zero_f.fx = 0.0;
  EXPECT_THROW (agex::depthImageToCloud (depth, zero_f, 0.001, cloud), agex::FrameError);
  agex::depthImageToCloud (depth, agex::CameraIntrinsics (), 0.001, cloud);
  EXPECT_EQ (cloud.size (), 16u);
  EXPECT_FLOAT_EQ (cloud (2, 2).z, 1.f);
}

TEST (FrameIo, IntrinsicsOutsideTheSaneRangeAreRefusedByName)
{
  // Focal lengths of 1e-6 px (metres-wide cells that crashed the person segmentation) and
  // 1e39 (finite as a double, infinite as a float: no detections without a word) are refused,
  // naming the intrinsic; so are a principal point and a depth scale beyond a float's range.
  Cloud cloud;
  const cv::Mat depth (4, 4, CV_16UC1, cv::Scalar (1000));
  auto refused = [&] (agex::CameraIntrinsics k, double scale, const std::string &needle) {
    expectFrameError ([&] { agex::depthImageToCloud (depth, k, scale, cloud); }, {needle});
  };
  agex::CameraIntrinsics k;
  for (const double f : {1e-6, 1e-30, 1e39, 2e6, -1.0})
  {
    k = agex::CameraIntrinsics ();
    k.fx = f;
    refused (k, 0.001, "fx must be a focal length of 0.001 to 1e+06 pixels");
    k = agex::CameraIntrinsics ();
    k.fy = f;
    refused (k, 0.001, "fy must be a focal length");
  }
  k = agex::CameraIntrinsics ();
  k.cy = 1e39;
  refused (k, 0.001, "cy must be a number of pixels finite as a float");
  refused (agex::CameraIntrinsics (), 1e39, "depth scale must be a positive number");
  EXPECT_EQ (agex::intrinsicProblem (agex::IntrinsicKind::kFocalLength, 1e-3), "");
  EXPECT_EQ (agex::intrinsicProblem (agex::IntrinsicKind::kFocalLength, 1e6), "");
  EXPECT_NE (agex::intrinsicProblem (agex::IntrinsicKind::kFocalLength, 1e-5), "");
  // Through loadFrame: the file named as well.
  TempDir dir;
  const std::string png = dir.file ("frame.png");
  cv::imwrite (png, cv::Mat (480, 640, CV_16UC1, cv::Scalar (1000)));
  agex::FrameOptions options;
  options.intrinsics.fx = 1e-6;
  expectFrameError ([&] { agex::loadFrame (png, options); }, {png, "fx must be a focal length"});
}

TEST (FrameIo, PointsBeyondAFloatAreInvalid)
{
  // 3e38 m at the principal point is a float; off-centre its x is not: NaN, never infinite.
  const cv::Mat depth (2, 2, CV_32FC1, cv::Scalar (3e38f));
  agex::CameraIntrinsics k;
  k.fx = k.fy = 0.5;
  k.cx = k.cy = 0.0;
  Cloud cloud;
  agex::depthImageToCloud (depth, k, 1.0, cloud);
  EXPECT_FLOAT_EQ (cloud (0, 0).z, 3e38f);
  for (const auto &p : cloud)
    EXPECT_TRUE ((std::isfinite (p.x) && std::isfinite (p.y) && std::isfinite (p.z)) || std::isnan (p.z));
  EXPECT_TRUE (std::isnan (cloud (1, 1).z));
}

TEST (FrameIo, FloatDepthImagesInMetresWithTheirInvalidValues)
{
  // A float image (metres, as numpy users hand it over), read through a row step wider than
  // the row: the left 4 x 3 of a 6 x 3 image, no copy; what lies right of it is never read.
  cv::Mat wide (3, 6, CV_32FC1, cv::Scalar (2.f));
  wide.at<float> (0, 1) = 0.f;
  wide.at<float> (1, 1) = -1.f;
  wide.at<float> (1, 2) = std::numeric_limits<float>::quiet_NaN ();
  wide.at<float> (2, 2) = std::numeric_limits<float>::infinity ();
  wide.at<float> (2, 4) = 7.f;
  const cv::Mat depth = wide (cv::Rect (0, 0, 4, 3));
  ASSERT_FALSE (depth.isContinuous ());
  agex::CameraIntrinsics k;
  k.fx = 100.0;
  k.fy = 200.0;
  k.cx = 1.0;
  k.cy = 1.0;
  Cloud cloud;
  agex::depthImageToCloud (depth, k, 1.0, cloud);
  ASSERT_EQ (cloud.width, 4u);
  ASSERT_EQ (cloud.height, 3u);
  EXPECT_FLOAT_EQ (cloud (3, 2).z, 2.f);
  EXPECT_FLOAT_EQ (cloud (3, 2).x, 2.f * 2.f / 100.f);
  EXPECT_FLOAT_EQ (cloud (3, 2).y, 1.f * 2.f / 200.f);
  EXPECT_FLOAT_EQ (cloud (0, 0).z, 2.f);
  for (const auto &[u, v] : std::vector<std::pair<int, int>>{{1, 0}, {1, 1}, {2, 1}, {2, 2}})
    EXPECT_TRUE (std::isnan (cloud (u, v).z)) << u << "," << v;
  // Millimetres as floats, with their scale.
  agex::depthImageToCloud (cv::Mat (2, 2, CV_32FC1, cv::Scalar (1500.f)), k, 0.001, cloud);
  EXPECT_FLOAT_EQ (cloud (1, 1).z, 1.5f);
  agex::CameraIntrinsics nan_cx = k;
  nan_cx.cx = std::nan ("");
  EXPECT_THROW (agex::depthImageToCloud (depth, nan_cx, 1.0, cloud), agex::FrameError);
}

// ---------------------------------------------------------------------------
// Real frames from ../shared (skipped without it)

TEST (FrameIo, SharedKinectFramesLoad)
{
  const std::string pcd = sharedData ("kinect/five_people.pcd");
  AGEX_REQUIRE_SHARED_FILE (pcd, "the Kinect test data (../shared/data/kinect)");
  const agex::Frame people = agex::loadFrame (pcd);
  EXPECT_EQ (people.cloud->width, 640u);
  EXPECT_EQ (people.cloud->height, 480u);
  std::size_t finite = 0;
  for (const auto &p : *people.cloud)
    if (isFinite (p))
    {
      ++finite;
      EXPECT_GT (p.z, 0.f);
    }
  EXPECT_GT (finite, 640u * 480u / 4);

  for (const auto &entry : fs::directory_iterator (sharedData ("kinect/skeltrack")))
  {
    if (entry.path ().extension () != ".u16")
      continue;
    SCOPED_TRACE (entry.path ().string ());
    const agex::Frame frame = agex::loadFrame (entry.path ().string ());
    ASSERT_EQ (frame.cloud->width, 640u);
    ASSERT_EQ (frame.cloud->height, 480u);
    std::size_t valid = 0;
    for (const auto &p : *frame.cloud)
      if (isFinite (p))
      {
        ++valid;
        EXPECT_TRUE (p.z > 0.5f && p.z < 3.5f) << p.z;  // upper bodies at 0.8-2.0 m
      }
    EXPECT_GT (valid, 1000u);
  }
}

TEST (FrameView, BonnPortraitViewCopiesSourcePoints)
{
  const std::string path = sharedData ("bonn/depth/1/002.png");
  AGEX_REQUIRE_BONN (path);
  const agex::Frame frame = agex::loadFrame (path);
  ASSERT_EQ (frame.cloud->width, 640u);
  ASSERT_EQ (frame.cloud->height, 480u);
  const agex::FrameView view = agex::bonnPortraitView ();
  Cloud portrait;
  agex::applyView (*frame.cloud, view, portrait);
  ASSERT_EQ (portrait.width, 144u);
  ASSERT_EQ (portrait.height, 176u);
  std::size_t finite = 0;
  for (int v = 0; v < 176; ++v)
    for (int u = 0; u < 144; ++u)
    {
      // Nearest source pixel of the output pixel's centre: crop x=140, y=20, scale 0.4.
      const int su = 140 + static_cast<int> (std::floor ((u + 0.5) / 0.4));
      const int sv = 20 + static_cast<int> (std::floor ((v + 0.5) / 0.4));
      ASSERT_EQ (view.sourcePixel (u, v), cv::Point (su, sv));
      ASSERT_TRUE (su < 500 && sv < 460);
      const pcl::PointXYZ &p = portrait (u, v), &s = (*frame.cloud) (su, sv);
      EXPECT_EQ (bits (p.x), bits (s.x));
      EXPECT_EQ (bits (p.y), bits (s.y));
      EXPECT_EQ (bits (p.z), bits (s.z));
      finite += isFinite (p);
    }
  EXPECT_GT (finite, 144u * 176u / 2);
  // toView maps a source pixel centre back onto the output pixel it feeds.
  const cv::Point2f back = view.toView (cv::Point2f (140 + 2.5f / 0.4f - 0.5f, 20 + 0.5f / 0.4f - 0.5f));
  EXPECT_NEAR (back.x, 2.f, 1e-4f);
  EXPECT_NEAR (back.y, 0.f, 1e-4f);

  agex::FrameView too_big = view;
  too_big.x = 300;  // 300 + 360 > 640
  expectFrameError ([&] { agex::applyView (*frame.cloud, too_big, portrait); }, {"does not fit"});
  Cloud flat;
  flat.push_back (pcl::PointXYZ (0.f, 0.f, 1.f));
  expectFrameError ([&] { agex::applyView (flat, view, portrait); }, {"organized"});
}

// ---------------------------------------------------------------------------
// Atomic output files

std::vector<std::string>
listDir (const fs::path &dir)
{
  std::vector<std::string> names;
  for (const auto &entry : fs::directory_iterator (dir))
    names.push_back (entry.path ().filename ().string ());
  std::sort (names.begin (), names.end ());
  return names;
}

TEST (AtomicFile, WritesAndReplaces)
{
  TempDir dir;
  const std::string path = dir.file ("out.json");
  agex::writeFileAtomic (path, "first\n");
  EXPECT_EQ (readAll (path), "first\n");
  struct stat st;
  ASSERT_EQ (::stat (path.c_str (), &st), 0);
  EXPECT_EQ (st.st_mode & 0777, 0644u);
  std::string binary (100000, '\0');
  for (std::size_t i = 0; i < binary.size (); ++i)
    binary[i] = static_cast<char> (i * 7);
  agex::writeFileAtomic (path, binary);
  EXPECT_EQ (readAll (path), binary);
  agex::writeFileAtomic (path, "");
  EXPECT_EQ (readAll (path), "");
  EXPECT_EQ (listDir (dir.path ()), std::vector<std::string> ({"out.json"})) << "no temporary files left";
}

TEST (AtomicFile, FailedWritesThrowAndKeepTheOldFile)
{
  TempDir dir;
  // Into a directory that does not exist.
  const std::string nowhere = dir.file ("missing/out.json");
  try
  {
    agex::writeFileAtomic (nowhere, "x");
    ADD_FAILURE () << "no exception";
  }
  catch (const std::runtime_error &e)
  {
    EXPECT_NE (std::string (e.what ()).find (nowhere), std::string::npos) << e.what ();
  }
  EXPECT_FALSE (fs::exists (dir.path () / "missing"));

  // A write that fails half-way (the file size limit stands in for a full disk):
  // the earlier output survives and no temporary file is left behind.
  const std::string path = dir.file ("out.json");
  agex::writeFileAtomic (path, "good old output\n");
  struct rlimit old_limit;
  ASSERT_EQ (::getrlimit (RLIMIT_FSIZE, &old_limit), 0);
  const auto old_handler = std::signal (SIGXFSZ, SIG_IGN);
  struct rlimit small = old_limit;
  small.rlim_cur = 4096;
  ASSERT_EQ (::setrlimit (RLIMIT_FSIZE, &small), 0);
  bool threw = false;
  try
  {
    agex::writeFileAtomic (path, std::string (1 << 20, 'x'));
  }
  catch (const std::runtime_error &e)
  {
    threw = true;
    EXPECT_NE (std::string (e.what ()).find (path), std::string::npos) << e.what ();
  }
  ::setrlimit (RLIMIT_FSIZE, &old_limit);
  std::signal (SIGXFSZ, old_handler);
  EXPECT_TRUE (threw) << "a failed write must throw";
  EXPECT_EQ (readAll (path), "good old output\n");
  EXPECT_EQ (listDir (dir.path ()), std::vector<std::string> ({"out.json"})) << "no temporary files left";

  // The target is a directory: the final rename fails; the directory is untouched.
  fs::create_directory (dir.path () / "taken");
  writeAll (dir.file ("taken/keep.txt"), "keep");
  EXPECT_THROW (agex::writeFileAtomic (dir.file ("taken"), "x"), std::runtime_error);
  EXPECT_EQ (readAll (dir.file ("taken/keep.txt")), "keep");
  EXPECT_EQ (listDir (dir.path ()), std::vector<std::string> ({"out.json", "taken"}));
}

TEST (AtomicFile, OutputMustNotBeAnInput)
{
  TempDir dir;
  const std::string input = dir.file ("frame.png");
  writeAll (input, "png");
  fs::create_directory (dir.path () / "sub");
  EXPECT_THROW (agex::checkOutputIsNotInput (input, {input}), std::runtime_error);
  // Other spellings of the same file.
  EXPECT_THROW (agex::checkOutputIsNotInput ((dir.path () / "sub" / ".." / "frame.png").string (), {input}),
                std::runtime_error);
  EXPECT_THROW (agex::checkOutputIsNotInput ((dir.path () / "." / "frame.png").string (), {"a.png", input}),
                std::runtime_error);
  // A directory holding an input (replaced with --force, it would take the input along).
  EXPECT_THROW (agex::checkOutputIsNotInput (dir.path ().string (), {input}), std::runtime_error);
  EXPECT_THROW (agex::checkOutputIsNotInput (dir.path ().parent_path ().string (), {input}), std::runtime_error);
  EXPECT_NO_THROW (agex::checkOutputIsNotInput ((dir.path () / "sub").string (), {input}));
  {
    // A relative spelling, from inside the directory.
    const fs::path cwd = fs::current_path ();
    fs::current_path (dir.path () / "sub");
    EXPECT_THROW (agex::checkOutputIsNotInput ("../frame.png", {input}), std::runtime_error);
    EXPECT_THROW (agex::checkOutputIsNotInput (input, {"./../sub/../frame.png"}), std::runtime_error);
    fs::current_path (cwd);
  }
  // Through a symbolic link.
  fs::create_symlink (input, dir.path () / "link.png");
  EXPECT_THROW (agex::checkOutputIsNotInput (dir.file ("link.png"), {input}), std::runtime_error);
  // Different files, including one that does not exist yet, are fine.
  EXPECT_NO_THROW (agex::checkOutputIsNotInput (dir.file ("out.json"), {input}));
  EXPECT_NO_THROW (agex::checkOutputIsNotInput (dir.file ("sub/frame.png"), {input}));
  EXPECT_NO_THROW (agex::checkOutputIsNotInput (input, {}));
  // Files that do not exist yet, spelled relative and differently (an image an app is about
  // to write, and an overlay aimed at it): weakly_canonical alone would keep them relative.
  agex::InputFiles planned ({"agex_not_there_yet/./images/a.png"});
  EXPECT_THROW (planned.checkOutput ((fs::current_path () / "agex_not_there_yet/images/a.png").string ()),
                std::runtime_error);
  EXPECT_THROW (planned.checkOutput ("agex_not_there_yet/images/../images/a.png"), std::runtime_error);
  EXPECT_THROW (planned.checkOutput ("agex_not_there_yet"), std::runtime_error);  // holds it
  EXPECT_NO_THROW (planned.checkOutput ("agex_not_there_yet/images/b.png"));
}

// ---------------------------------------------------------------------------
// 8. InterestPoint PCD round trip

TEST (InterestPointIo, PcdRoundTripKeepsEveryField)
{
  TempDir dir;
  pcl::PointCloud<agex::InterestPoint> cloud;
  std::mt19937 rng (8);
  std::uniform_real_distribution<float> uni (-3.f, 3.f);
  for (int i = 0; i < 9; ++i)
  {
    agex::InterestPoint p;
    p.x = uni (rng);
    p.y = uni (rng);
    p.z = 1.f + std::abs (uni (rng));
    p.orientation[0] = uni (rng);
    p.orientation[1] = uni (rng);
    p.orientation[2] = i == 0 ? 0.f : uni (rng);
    p.geodesic_distance = std::abs (uni (rng));
    p.rank = i % 5 + 1;
    p.mesh = i / 5;
    p.u = 100 * i - 3;  // negative too
    p.v = 1 << (i + 10);
    cloud.push_back (p);
  }
  for (bool compressed : {false, true})
  {
    SCOPED_TRACE (compressed ? "binary_compressed" : "binary");
    const std::string path = dir.file (compressed ? "points_c.pcd" : "points.pcd");
    ASSERT_EQ (compressed ? pcl::io::savePCDFileBinaryCompressed (path, cloud) : pcl::io::savePCDFileBinary (path, cloud), 0);
    pcl::PointCloud<agex::InterestPoint> back;
    ASSERT_EQ (pcl::io::loadPCDFile (path, back), 0);
    ASSERT_EQ (back.size (), cloud.size ());
    EXPECT_EQ (back.width, cloud.width);
    EXPECT_EQ (back.height, 1u);
    for (std::size_t i = 0; i < cloud.size (); ++i)
    {
      const auto &a = cloud[i], &b = back[i];
      SCOPED_TRACE ("point " + std::to_string (i));
      EXPECT_EQ (bits (a.x), bits (b.x));
      EXPECT_EQ (bits (a.y), bits (b.y));
      EXPECT_EQ (bits (a.z), bits (b.z));
      for (int c = 0; c < 3; ++c)
        EXPECT_EQ (bits (a.orientation[c]), bits (b.orientation[c])) << "orientation " << c;
      EXPECT_EQ (bits (a.geodesic_distance), bits (b.geodesic_distance));
      EXPECT_EQ (a.rank, b.rank);
      EXPECT_EQ (a.mesh, b.mesh);
      EXPECT_EQ (a.u, b.u);
      EXPECT_EQ (a.v, b.v);
    }
  }
  // The header names every field, with orientation as a 3-element field.
  const std::string text = readAll (dir.file ("points.pcd"));
  EXPECT_NE (text.find ("FIELDS x y z orientation geodesic_distance rank mesh u v"), std::string::npos) << text.substr (0, 300);
  EXPECT_NE (text.find ("COUNT 1 1 1 3 1 1 1 1 1"), std::string::npos);
}
}  // namespace
