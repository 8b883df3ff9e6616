#include <agex/apps/live_runs.h>

#include <agex/apps/command_line.h>
#include <agex/apps/results_file.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <iostream>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <thread>

#include <pthread.h>
#include <signal.h>

namespace agex
{
namespace apps
{
namespace
{
/** Turns SIGINT and SIGTERM into a stop of the source: they are blocked in this thread (and
  * so in every thread started after, the source's too) and taken by a watcher thread, which
  * may safely stop the source (a signal handler could not take its lock). */
class StopOnSignals
{
public:
  explicit StopOnSignals (std::string app) : app_ (std::move (app))
  {
    sigemptyset (&signals_);
    sigaddset (&signals_, SIGINT);
    sigaddset (&signals_, SIGTERM);
    pthread_sigmask (SIG_BLOCK, &signals_, &previous_);
    watcher_ = std::thread ([this] { watch (); });
  }
  ~StopOnSignals ()
  {
    done_ = true;
    watcher_.join ();
    pthread_sigmask (SIG_SETMASK, &previous_, nullptr);
  }
  void attach (FrameSource *source)
  {
    std::lock_guard<std::mutex> lock (mutex_);
    source_ = source;
    if (source_ && signalled_)
      source_->stop ();
  }
  bool signalled () const { return signalled_; }

private:
  void watch ()
  {
    const timespec tick{0, 100 * 1000 * 1000};
    while (!done_)
    {
      const int signal = sigtimedwait (&signals_, nullptr, &tick);
      if (signal <= 0)
        continue;
      if (signalled_)
      {
        std::fprintf (stderr, "%s: stopped at once (a second signal)\n", app_.c_str ());
        std::_Exit (130);
      }
      signalled_ = true;
      std::fprintf (stderr, "%s: stopping: the frames in hand finish and are written (again to stop at once)\n",
                    app_.c_str ());
      std::lock_guard<std::mutex> lock (mutex_);
      if (source_)
        source_->stop ();
    }
  }

  std::string app_;
  sigset_t signals_, previous_;
  std::mutex mutex_;
  FrameSource *source_ = nullptr;
  std::atomic<bool> done_{false}, signalled_{false};
  std::thread watcher_;
};

FrameSource::Ptr
openDevice (const std::string &device, double fps, const FrameOptions &options)
{
  if (device == "openni2")
    return openOpenNI2 ("");
  if (device.rfind ("openni2:", 0) == 0)
    return openOpenNI2 (device.substr (8));
  if (device.rfind ("replay:", 0) == 0 && device.size () > 7)
    return replayAtRate (openFrames (device.substr (7), options), fps);
  throw std::runtime_error ("--device takes openni2, openni2:URI (a device URI, #N for the N-th device, or an .oni "
                            "recording) or replay:PATH (frames replayed at --fps), not '" + device + "'");
}
}  // namespace

Frame
liveFrame (const SourceFrame &source)
{
  Frame frame;
  frame.path = source.path.empty () ? source.name : source.path;
  frame.cloud = source.cloud;
  frame.intrinsics = source.intrinsics;
  frame.from_depth_image = source.has_intrinsics;
  return frame;
}

int
runLiveDetection (const std::string &device, double fps, const FrameOptions &options, const std::string &json_path,
                  int threads, const std::string &app, const std::function<nlohmann::json (const SourceFrame &)> &process)
{
  if (!(fps >= kMinReplayFps && fps <= kMaxReplayFps))
    throw std::runtime_error ("--fps must lie in [0.1, 1000] frames per second");
  // Before the source starts its threads, so that they leave the signals to the watcher.
  StopOnSignals stop (app);
  std::unique_ptr<ResultsFile> results;
  if (!json_path.empty ())
    results = std::make_unique<ResultsFile> (json_path, app);
  const FrameSource::Ptr source = openDevice (device, fps, options);
  stop.attach (source.get ());
  std::cerr << app << ": " << source->describe () << ": processing frames as they arrive (Ctrl-C stops)\n";

  std::mutex mutex;
  std::string first_error;
  std::atomic<std::size_t> processed{0};
  const auto start = std::chrono::steady_clock::now ();
  auto worker = [&] () {
    SourceFrame frame;
    for (;;)
    {
      std::string line;
      try
      {
        if (!source->next (frame))
          return;
        nlohmann::json doc = process (frame);
        doc["sequence"] = frame.sequence;
        doc["timestamp"] = frame.timestamp;
        doc["dropped"] = source->dropped ();
        line = doc.dump ();
        if (results)
          results->append (line);
      }
      catch (const std::exception &e)
      {
        std::lock_guard<std::mutex> lock (mutex);
        if (first_error.empty ())
          first_error = e.what ();
        source->stop ();
        return;
      }
      std::lock_guard<std::mutex> lock (mutex);
      if (!results)
        std::cout << line << "\n" << std::flush;
      ++processed;
    }
  };
  runWorkers (threads, static_cast<std::size_t> (threads), worker);
  const double seconds = std::chrono::duration<double> (std::chrono::steady_clock::now () - start).count ();
  stop.attach (nullptr);

  char summary[256];
  std::snprintf (summary, sizeof summary, "%zu frames processed, %llu dropped, in %.1f s (%.1f frames/s)",
                 processed.load (), static_cast<unsigned long long> (source->dropped ()), seconds,
                 seconds > 0.0 ? processed / seconds : 0.0);
  std::cerr << app << ": " << source->describe () << ": " << summary
            << (stop.signalled () ? "; stopped by a signal" : first_error.empty () ? "; the source ended" : "") << "\n";
  if (!first_error.empty ())
    throw std::runtime_error (first_error + (results && processed > 0 ? " (the frames done are in " + results->path () + ")"
                                                                       : std::string ()));
  return 0;
}
}  // namespace apps
}  // namespace agex
