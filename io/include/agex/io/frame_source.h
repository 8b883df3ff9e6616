#pragma once
// Frames one after another, wherever they come from: frame files, a directory of them, an
// agex dataset, a numbered image sequence, a replay of any of these at a set frame rate, or a
// live OpenNI2 depth camera (pcl::io::OpenNI2Grabber, also for .oni recordings). A live
// source never queues: a frame the consumer has not taken when the next one arrives is
// dropped, and counted.

#include <agex/io/frame_io.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <condition_variable>
#include <cstdint>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace agex
{
/** One frame of a FrameSource. */
struct SourceFrame
{
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud;  ///< organized, metres, NaN = invalid; the consumer's own
  /** The camera's pinhole intrinsics (depth images, datasets, cameras); has_intrinsics is
    * false for PCD files, which carry their points but no camera. */
  CameraIntrinsics intrinsics;
  bool has_intrinsics = false;
  /** Seconds: a camera's own time stamp; a replay's time since it started; 0 for sources
    * without a clock (files, directories, datasets, image sequences). */
  double timestamp = 0.0;
  /** 0-based number of the frame among all the source produced, dropped frames included
    * (a gap in the sequence is a drop). */
  std::uint64_t sequence = 0;
  /** A name for outputs: "<directory name>/<file name>" for a file, "<dataset>/<frame id>"
    * for a dataset's frame, "<device>/<sequence>" for a camera. */
  std::string name;
  std::string path;  ///< the file it was loaded from (empty for a camera)
};

/** \brief A source of organized depth frames, one after another.
  *
  * next () blocks until the next frame and returns false at the end of the source or once
  * stop () was called; stop () may be called from any thread (e.g. one that watches for
  * Ctrl-C) while another waits in next (). Only one consumer at a time is meant to call
  * next () on sources that are not live (they read files as asked); live sources may serve
  * several consumers.
  */
class FrameSource
{
public:
  using Ptr = std::unique_ptr<FrameSource>;
  virtual ~FrameSource () = default;

  /** \brief The next frame. \return false at the end or after stop ()
    * \throws FrameError naming the frame (file, device) that could not be read */
  virtual bool next (SourceFrame &frame) = 0;
  /** Ends the source: a waiting or later next () returns false. Safe from any thread. */
  virtual void stop () = 0;
  /** Whether frames arrive on the source's own clock, so that a slow consumer loses some. */
  virtual bool live () const { return false; }
  /** Frames a live source discarded because the previous one had not been taken yet. */
  virtual std::uint64_t dropped () const { return 0; }
  /** What the source reads, for messages (e.g. "directory data/frames (3 frames)"). */
  virtual std::string describe () const = 0;
};

/** \brief The frame files in the order given (loadFrame with options; names as agex_detect's).
  * \throws FrameError if the list is empty */
FrameSource::Ptr openFrameFiles (const std::vector<std::string> &paths, const FrameOptions &options = FrameOptions ());

/** \brief The frame files (.pcd, .png, .u16) of a directory, sorted by name.
  * \throws FrameError naming the directory if it is missing or holds no frames */
FrameSource::Ptr openFrameDirectory (const std::string &directory, const FrameOptions &options = FrameOptions ());

/** \brief The frames of an agex dataset in its order, with its intrinsics.
  * \throws DatasetError naming the file and the problem */
FrameSource::Ptr openDatasetFrames (const std::string &directory);

/** \brief A numbered image sequence, as a video: pattern holds one printf conversion of a
  * frame number (%d, or %0Nd with N up to 9; "%%" is a literal %), e.g.
  * "depth/frame_%05d.png". Frames are read from number first on until the first number with
  * no file (at least one must exist).
  * \throws FrameError naming the pattern when it is malformed or its first frame is missing */
FrameSource::Ptr openImageSequence (const std::string &pattern, const FrameOptions &options = FrameOptions (),
                                    int first = 0);

/** \brief Whichever of the above spec names: a dataset directory, a directory of frames,
  * a pattern with a %-conversion, or a frame file.
  * \throws FrameError (DatasetError for a dataset) naming spec */
FrameSource::Ptr openFrames (const std::string &spec, const FrameOptions &options = FrameOptions ());

/** The frame rates a replay takes (frames per second). */
constexpr double kMinReplayFps = 0.1, kMaxReplayFps = 1000.0;

/** \brief Replays another source at a set frame rate, as a camera would deliver it: frame i
  * is offered i / fps seconds after the start (its timestamp), whether or not the consumer
  * took frame i - 1; an untaken frame is replaced and counted in dropped (). The replay ends
  * with its source; an error of the source is thrown by next () once the frames before it
  * are taken. Testing and timing a live consumer needs no camera.
  * \throws std::invalid_argument unless fps lies in [kMinReplayFps, kMaxReplayFps] */
FrameSource::Ptr replayAtRate (FrameSource::Ptr source, double fps);

/** Whether this agex was built with OpenNI2 support (PCL's io built with OpenNI2, and its
  * pcl/io/openni2_grabber.h present at build time). */
bool openNI2Supported ();

/** \brief A live OpenNI2 depth camera (pcl::io::OpenNI2Grabber): uri "" for the first device,
  * "#N" for the N-th, a device URI, or the path of an .oni recording. Frames are
  * pcl::PointXYZ clouds with the device's depth intrinsics and time stamps, named
  * "openni2/<sequence>".
  * \throws FrameError naming what was tried: no device (with the number OpenNI2 sees), a
  *         device that cannot be opened, or a build without OpenNI2 */
FrameSource::Ptr openOpenNI2 (const std::string &uri);

/** \brief The single-frame mailbox between a live producer (a camera's callback, a replay's
  * clock) and its consumers: put () replaces a frame no consumer has taken yet and counts it
  * as dropped, so a slow consumer always gets the newest frame and nothing queues up. */
class LatestFrameSlot
{
public:
  /** Offers a frame; an untaken one is replaced (a drop). Ignored after close or abort. */
  void put (SourceFrame frame);
  /** \brief Waits for a frame. \return false once closed and empty, or aborted
    * \throws the error given to close (), once the frames before it are taken */
  bool take (SourceFrame &frame);
  /** No more frames: the one waiting may still be taken; then take () throws error if set,
    * else returns false. */
  void close (std::exception_ptr error = nullptr);
  /** Stop now: the waiting frame is discarded, every take () returns false. */
  void abort ();
  std::uint64_t dropped () const;

private:
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  SourceFrame frame_;
  bool full_ = false, closed_ = false, aborted_ = false;
  std::exception_ptr error_;
  std::uint64_t dropped_ = 0;
};
}  // namespace agex
