// Frame sources: files, directories, datasets and image sequences in order with their names and
// intrinsics; malformed patterns refused; a replay at a set frame rate that drops (and counts)
// the frames a slow consumer misses, stops from another thread, and reports a bad frame after
// the good ones; OpenNI2 without a camera says what it tried.

#include "test_support.h"

#include <agex/io/dataset.h>
#include <agex/io/frame_source.h>

#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <future>
#include <thread>

namespace
{
using agex_test::TempDir;

/** A 16-bit depth PNG of 4x3 pixels, every pixel `millimetres` (0 = invalid). */
void
writeDepthPng (const std::string &path, int millimetres)
{
  cv::Mat depth (3, 4, CV_16UC1, cv::Scalar (millimetres));
  depth.at<std::uint16_t> (0, 0) = 0;
  ASSERT_TRUE (cv::imwrite (path, depth));
}

agex::FrameOptions
smallFrameOptions ()
{
  agex::FrameOptions options;
  options.intrinsics = {100.0, 110.0, 1.5, 1.0};
  options.intrinsics_width = options.intrinsics_height = 0;  // the intrinsics are for any size
  return options;
}

std::vector<agex::SourceFrame>
drain (agex::FrameSource &source)
{
  std::vector<agex::SourceFrame> frames;
  agex::SourceFrame frame;
  while (source.next (frame))
    frames.push_back (frame);
  return frames;
}

TEST (FrameSource, DirectoryInNameOrderWithNamesAndIntrinsics)
{
  TempDir dir;
  const auto frames_dir = dir.path () / "cam";
  std::filesystem::create_directories (frames_dir);
  writeDepthPng ((frames_dir / "b.png").string (), 2000);
  writeDepthPng ((frames_dir / "a.png").string (), 1000);
  writeDepthPng ((frames_dir / "c.png").string (), 3000);
  agex_test::writeAll ((frames_dir / "notes.txt").string (), "not a frame");
  auto source = agex::openFrames (frames_dir.string (), smallFrameOptions ());
  EXPECT_FALSE (source->live ());
  const auto frames = drain (*source);
  ASSERT_EQ (frames.size (), 3u);
  const char *names[] = {"cam/a.png", "cam/b.png", "cam/c.png"};
  for (std::size_t i = 0; i < frames.size (); ++i)
  {
    EXPECT_EQ (frames[i].name, names[i]);
    EXPECT_EQ (frames[i].sequence, i);
    EXPECT_TRUE (frames[i].has_intrinsics);
    EXPECT_DOUBLE_EQ (frames[i].intrinsics.fy, 110.0);
    ASSERT_EQ (frames[i].cloud->width, 4u);
    EXPECT_FLOAT_EQ ((*frames[i].cloud) (1, 1).z, 1.0f * (i + 1));
    EXPECT_TRUE (std::isnan ((*frames[i].cloud) (0, 0).z));
  }
  EXPECT_EQ (source->dropped (), 0u);

  EXPECT_THROW (agex::openFrameDirectory ((dir.path () / "missing").string ()), agex::FrameError);
  std::filesystem::create_directories (dir.path () / "empty");
  try
  {
    agex::openFrameDirectory ((dir.path () / "empty").string ());
    ADD_FAILURE () << "an empty directory was accepted";
  }
  catch (const agex::FrameError &e)
  {
    EXPECT_NE (std::string (e.what ()).find ("no frames"), std::string::npos) << e.what ();
  }
}

TEST (FrameSource, ImageSequenceUntilTheFirstGap)
{
  TempDir dir;
  for (int i : {3, 4, 5, 7})
  {
    char name[32];
    std::snprintf (name, sizeof name, "depth_%04d.png", i);
    writeDepthPng (dir.file (name), 1000 + i);
  }
  const std::string pattern = dir.file ("depth_%04d.png");
  auto source = agex::openImageSequence (pattern, smallFrameOptions (), 3);
  const auto frames = drain (*source);
  ASSERT_EQ (frames.size (), 3u);  // 3, 4, 5; 6 is missing, so 7 is not reached
  EXPECT_NE (frames[2].path.find ("depth_0005.png"), std::string::npos);
  EXPECT_FLOAT_EQ ((*frames[2].cloud) (1, 1).z, 1.005f);
  EXPECT_EQ (frames[2].sequence, 2u);

  // The first frame must exist, and the pattern holds exactly one frame number.
  EXPECT_THROW (agex::openImageSequence (pattern, smallFrameOptions (), 0), agex::FrameError);
  for (const std::string bad : {"f_%s.png", "f_%d_%d.png", "f.png", "f_%5d.png", "f_%010d.png", "f_%0d.png", "f_%"})
    EXPECT_THROW (agex::openImageSequence (dir.file (bad), smallFrameOptions (), 3), agex::FrameError) << bad;
  // %% is a literal percent sign.
  writeDepthPng (dir.file ("p%_0.png"), 1500);
  EXPECT_EQ (drain (*agex::openImageSequence (dir.file ("p%%_%d.png"), smallFrameOptions ())).size (), 1u);
}

TEST (FrameSource, DatasetFramesWithItsIntrinsics)
{
  TempDir dir;
  agex::DatasetInfo info;
  info.name = "tiny";
  info.sensor = "test";
  info.width = 4;
  info.height = 3;
  info.intrinsics = {50.0, 51.0, 1.5, 1.0};
  const std::string directory = dir.file ("tiny");
  {
    agex::DatasetWriter writer (directory, info);
    for (const char *id : {"f0", "f1"})
    {
      pcl::PointCloud<pcl::PointXYZ> cloud (4, 3, pcl::PointXYZ (0.f, 0.f, 1.5f));
      writer.addFrame (id, "s", cloud, {});
    }
    writer.commit ();
  }
  auto source = agex::openFrames (directory);
  const auto frames = drain (*source);
  ASSERT_EQ (frames.size (), 2u);
  EXPECT_EQ (frames[1].name, "tiny/f1");
  EXPECT_TRUE (frames[1].has_intrinsics);
  EXPECT_DOUBLE_EQ (frames[1].intrinsics.fy, 51.0);
  EXPECT_FLOAT_EQ ((*frames[1].cloud) (2, 1).z, 1.5f);
  EXPECT_NE (source->describe ().find ("2 frames"), std::string::npos);
}

TEST (FrameSource, MissingSpecNamed)
{
  try
  {
    agex::openFrames ("/nonexistent/agex/frames");
    ADD_FAILURE () << "a missing path was accepted";
  }
  catch (const agex::FrameError &e)
  {
    EXPECT_NE (std::string (e.what ()).find ("/nonexistent/agex/frames"), std::string::npos);
  }
  EXPECT_THROW (agex::openFrameFiles ({}), agex::FrameError);
}

TEST (LatestFrameSlot, ReplacesAnUntakenFrameAndCountsIt)
{
  agex::LatestFrameSlot slot;
  agex::SourceFrame a, b, got;
  a.sequence = 1;
  b.sequence = 2;
  slot.put (a);
  slot.put (b);
  EXPECT_EQ (slot.dropped (), 1u);
  ASSERT_TRUE (slot.take (got));
  EXPECT_EQ (got.sequence, 2u);
  slot.close (std::make_exception_ptr (agex::FrameError ("broken camera")));
  EXPECT_THROW (slot.take (got), agex::FrameError);
  slot.put (a);  // ignored once closed
  EXPECT_EQ (slot.dropped (), 1u);
}

/** A directory of n small frames. */
std::string
frameDirectory (const TempDir &dir, int n)
{
  const auto frames = dir.path () / "frames";
  std::filesystem::create_directories (frames);
  for (int i = 0; i < n; ++i)
  {
    char name[32];
    std::snprintf (name, sizeof name, "%03d.png", i);
    writeDepthPng ((frames / name).string (), 1000 + i);
  }
  return frames.string ();
}

TEST (ReplaySource, AConsumerThatKeepsUpGetsEveryFrameInOrder)
{
  TempDir dir;
  auto source = agex::replayAtRate (agex::openFrameDirectory (frameDirectory (dir, 5), smallFrameOptions ()), 10.0);
  EXPECT_TRUE (source->live ());
  const auto frames = drain (*source);  // 100 ms between frames, and nothing to do with them
  ASSERT_EQ (frames.size (), 5u);
  for (std::size_t i = 0; i < frames.size (); ++i)
  {
    EXPECT_EQ (frames[i].sequence, i);
    EXPECT_DOUBLE_EQ (frames[i].timestamp, i / 10.0);
    EXPECT_FLOAT_EQ ((*frames[i].cloud) (1, 1).z, 1.0f + 0.001f * i);
  }
  EXPECT_EQ (source->dropped (), 0u);
}

TEST (ReplaySource, ASlowConsumerLosesFramesAndTheyAreCounted)
{
  TempDir dir;
  constexpr int kFrames = 20;
  // 200 frames per second (5 ms apart); the consumer needs 60 ms per frame.
  auto source = agex::replayAtRate (agex::openFrameDirectory (frameDirectory (dir, kFrames), smallFrameOptions ()), 200.0);
  std::vector<std::uint64_t> sequences;
  agex::SourceFrame frame;
  while (source->next (frame))
  {
    sequences.push_back (frame.sequence);
    std::this_thread::sleep_for (std::chrono::milliseconds (60));
  }
  ASSERT_FALSE (sequences.empty ());
  EXPECT_EQ (sequences.size () + source->dropped (), static_cast<std::size_t> (kFrames));
  EXPECT_GE (source->dropped (), static_cast<std::uint64_t> (kFrames / 2));
  EXPECT_EQ (sequences.back (), static_cast<std::uint64_t> (kFrames - 1));  // the newest frame is never lost
  std::uint64_t gaps = 0;
  for (std::size_t i = 1; i < sequences.size (); ++i)
  {
    ASSERT_GT (sequences[i], sequences[i - 1]);
    gaps += sequences[i] - sequences[i - 1] - 1;
  }
  EXPECT_EQ (gaps + sequences.front (), source->dropped ());
}

TEST (ReplaySource, StopsFromAnotherThreadWhileTheConsumerWaits)
{
  TempDir dir;
  // One frame per 10 s (the slowest rate): the consumer would wait for the second one.
  auto source = agex::replayAtRate (agex::openFrameDirectory (frameDirectory (dir, 3), smallFrameOptions ()), 0.1);
  agex::SourceFrame frame;
  ASSERT_TRUE (source->next (frame));
  auto waiting = std::async (std::launch::async, [&] { return source->next (frame); });
  std::this_thread::sleep_for (std::chrono::milliseconds (50));
  source->stop ();
  ASSERT_EQ (waiting.wait_for (std::chrono::seconds (10)), std::future_status::ready);
  EXPECT_FALSE (waiting.get ());
  EXPECT_FALSE (source->next (frame));
}

TEST (ReplaySource, ABadFrameIsReportedAfterTheGoodOnes)
{
  TempDir dir;
  const std::string frames = frameDirectory (dir, 2);
  agex_test::writeAll (frames + "/002.png", "not a png");
  auto source = agex::replayAtRate (agex::openFrameDirectory (frames, smallFrameOptions ()), 50.0);
  agex::SourceFrame frame;
  ASSERT_TRUE (source->next (frame));
  ASSERT_TRUE (source->next (frame));
  try
  {
    source->next (frame);
    ADD_FAILURE () << "the bad frame was not reported";
  }
  catch (const agex::FrameError &e)
  {
    EXPECT_NE (std::string (e.what ()).find ("002.png"), std::string::npos) << e.what ();
  }
  EXPECT_THROW (agex::replayAtRate (agex::openFrameDirectory (frames, smallFrameOptions ()), 0.0), std::invalid_argument);
}

TEST (ReplaySource, RatesWhoseScheduleOverflowsAreRefused)
{
  TempDir dir;
  const std::string frames = frameDirectory (dir, 2);
  // 1e-10 fps ran at full speed (frame i's due time overflowed), 1e-9 waited 31 years a frame.
  for (const double fps : {1e-10, 1e-9, 5e-324, 0.099, 1000.5, 1e300})
    EXPECT_THROW (agex::replayAtRate (agex::openFrameDirectory (frames, smallFrameOptions ()), fps), std::invalid_argument)
        << fps;
  EXPECT_NO_THROW (agex::replayAtRate (agex::openFrameDirectory (frames, smallFrameOptions ()), agex::kMinReplayFps));
  EXPECT_NO_THROW (agex::replayAtRate (agex::openFrameDirectory (frames, smallFrameOptions ()), agex::kMaxReplayFps));
}

TEST (OpenNI2Source, WithoutACameraSaysWhatItTried)
{
  // This test machine has no depth camera; with one plugged in there is nothing to check here.
  try
  {
    auto source = agex::openOpenNI2 ("");
    GTEST_SKIP () << "a depth camera is connected: " << source->describe ();
  }
  catch (const agex::FrameError &e)
  {
    const std::string message = e.what ();
    EXPECT_NE (message.find ("openni2"), std::string::npos) << message;
    EXPECT_NE (message.find ("tried"), std::string::npos) << message;
  }
  // A recording that does not exist is named.
  try
  {
    agex::openOpenNI2 ("/nonexistent/recording.oni");
    ADD_FAILURE () << "a missing recording was opened";
  }
  catch (const agex::FrameError &e)
  {
    EXPECT_NE (std::string (e.what ()).find ("/nonexistent/recording.oni"), std::string::npos) << e.what ();
  }
}
}  // namespace
