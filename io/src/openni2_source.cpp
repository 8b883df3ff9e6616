// The live OpenNI2 camera source. Built with OpenNI2 (AGEX_WITH_OPENNI2) when PCL's io has
// pcl::io::OpenNI2Grabber; otherwise openOpenNI2 says that this build cannot open one.

#include <agex/io/frame_source.h>

#include <cmath>
#include <filesystem>
#include <cstdio>
#include <sstream>

#ifdef AGEX_WITH_OPENNI2
#include <pcl/io/openni2/openni2_device.h>
#include <pcl/io/openni2/openni2_device_manager.h>
#include <pcl/io/openni2_grabber.h>
#include <pcl/exceptions.h>

#include <boost/signals2/connection.hpp>
#endif

namespace agex
{
#ifdef AGEX_WITH_OPENNI2
namespace
{
std::string
deviceName (const std::string &uri)
{
  return uri.empty () ? "openni2 (the first device)" : "openni2:" + uri;
}

class OpenNI2Source : public FrameSource
{
public:
  explicit OpenNI2Source (const std::string &uri) : uri_ (uri)
  {
    const std::string tried = deviceName (uri) + " through pcl::io::OpenNI2Grabber";
    std::size_t devices = 0;
    try
    {
      devices = pcl::io::openni2::OpenNI2DeviceManager::getInstance ()->getNumOfConnectedDevices ();
    }
    catch (const std::exception &e)
    {
      throw FrameError ("no depth camera: tried " + tried + "; OpenNI2 could not list devices: " + e.what ());
    }
    // An .oni recording needs no connected device.
    const bool recording = uri.size () > 4 && uri.compare (uri.size () - 4, 4, ".oni") == 0;
    std::error_code ec;
    if (recording && !std::filesystem::is_regular_file (uri, ec))
      throw FrameError ("no depth camera: tried " + tried + " to play the OpenNI2 recording " + uri +
                        ", which is not a file");
    if (devices == 0 && !recording)
      throw FrameError ("no depth camera: tried " + tried + ", and OpenNI2 sees no connected device (is one "
                        "plugged in, powered, and readable by this user?)");
    try
    {
      grabber_ = std::make_unique<pcl::io::OpenNI2Grabber> (uri);
      if (!grabber_->providesCallback<pcl::io::OpenNI2Grabber::sig_cb_openni_point_cloud> ())
        throw FrameError ("the device gives no depth point clouds");
      std::function<pcl::io::OpenNI2Grabber::sig_cb_openni_point_cloud> callback =
          [this] (const pcl::PointCloud<pcl::PointXYZ>::ConstPtr &cloud) { arrive (cloud); };
      connection_ = grabber_->registerCallback (callback);
      grabber_->start ();
    }
    catch (const FrameError &e)
    {
      throw FrameError ("cannot use the depth camera: tried " + tried + " (OpenNI2 sees " + std::to_string (devices) +
                        " device(s)): " + e.what ());
    }
    catch (const std::exception &e)
    {
      throw FrameError ("cannot open the depth camera: tried " + tried + " (OpenNI2 sees " +
                        std::to_string (devices) + " device(s)): " + e.what ());
    }
  }
  ~OpenNI2Source () override
  {
    stop ();
    connection_.disconnect ();
  }
  bool next (SourceFrame &frame) override { return slot_.take (frame); }
  void stop () override
  {
    slot_.abort ();
    std::lock_guard<std::mutex> lock (stop_mutex_);
    if (grabber_ && grabber_->isRunning ())
      grabber_->stop ();
  }
  bool live () const override { return true; }
  std::uint64_t dropped () const override { return slot_.dropped (); }
  std::string describe () const override { return deviceName (uri_); }

private:
  void arrive (const pcl::PointCloud<pcl::PointXYZ>::ConstPtr &cloud)
  {
    if (!cloud || !cloud->isOrganized ())
      return;
    SourceFrame frame;
    // The consumer owns its frame (it may change it); PCL's stays the grabber's.
    frame.cloud.reset (new pcl::PointCloud<pcl::PointXYZ> (*cloud));
    frame.sequence = sequence_++;
    frame.timestamp = static_cast<double> (cloud->header.stamp) * 1e-6;  // PCL stamps are microseconds
    char name[32];
    std::snprintf (name, sizeof name, "openni2/%06llu", static_cast<unsigned long long> (frame.sequence));
    frame.name = name;
    frame.has_intrinsics = intrinsics (*cloud, frame.intrinsics);
    slot_.put (std::move (frame));
  }

  /** The intrinsics the grabber back-projected with: those set on it, else the device's
    * focal length with the image centre (what PCL's grabber then uses). */
  bool intrinsics (const pcl::PointCloud<pcl::PointXYZ> &cloud, CameraIntrinsics &k) const
  {
    double fx, fy, cx, cy;
    grabber_->getDepthCameraIntrinsics (fx, fy, cx, cy);
    if (!std::isfinite (fx) || !std::isfinite (fy))
    {
      const auto device = grabber_->getDevice ();
      fx = fy = device ? device->getDepthFocalLength () : 0.0;
    }
    k.fx = fx;
    k.fy = fy;
    k.cx = std::isfinite (cx) ? cx : (cloud.width - 1) / 2.0;
    k.cy = std::isfinite (cy) ? cy : (cloud.height - 1) / 2.0;
    return k.fx > 0.0 && k.fy > 0.0;
  }

  std::string uri_;
  std::unique_ptr<pcl::io::OpenNI2Grabber> grabber_;
  boost::signals2::connection connection_;
  LatestFrameSlot slot_;
  std::uint64_t sequence_ = 0;  // written by the grabber's thread only
  std::mutex stop_mutex_;
};
}  // namespace

bool
openNI2Supported ()
{
  return true;
}

FrameSource::Ptr
openOpenNI2 (const std::string &uri)
{
  return std::make_unique<OpenNI2Source> (uri);
}
#else
bool
openNI2Supported ()
{
  return false;
}

FrameSource::Ptr
openOpenNI2 (const std::string &uri)
{
  throw FrameError ("no depth camera: tried openni2" + (uri.empty () ? std::string () : ":" + uri) +
                    ", but this agex was built without OpenNI2 (PCL's io had no pcl/io/openni2_grabber.h, or PCL was "
                    "built without OpenNI2)");
}
#endif
}  // namespace agex
