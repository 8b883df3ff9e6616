// Frame input (8/16-bit PNG, raw .u16, organized PCD), the portrait view, atomic
// output files and agex::InterestPoint PCD round trips.

#include "test_support.h"

#include <agex/common/atomic_file.h>
#include <agex/common/frame_io.h>

#include <pcl/io/pcd_io.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <csignal>
#include <fstream>
#include <random>
#include <sstream>

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

  const agex::Frame frame = agex::loadFrame (path);
  EXPECT_EQ (frame.path, path);
  EXPECT_TRUE (frame.from_depth_image);
  EXPECT_DOUBLE_EQ (frame.depth_scale, 0.016) << "documented default scale of 8-bit (Bonn) PNGs";
  expectBackProjection (depth, frame, 0.016, agex::CameraIntrinsics ());

  agex::FrameOptions options;
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
  const agex::Frame frame = agex::loadFrame (path);
  EXPECT_DOUBLE_EQ (frame.depth_scale, 0.001) << "16-bit PNGs default to millimetres";
  expectBackProjection (depth, frame, 0.001, agex::CameraIntrinsics ());
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
  EXPECT_THROW (agex::depthImageToCloud (cv::Mat (4, 4, CV_32FC1), agex::CameraIntrinsics (), 0.001, cloud),
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
