#include <agex/io/dataset.h>
#include <agex/io/frame_source.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace fs = std::filesystem;

namespace agex
{
// ---------------------------------------------------------------------------------------
void
LatestFrameSlot::put (SourceFrame frame)
{
  {
    std::lock_guard<std::mutex> lock (mutex_);
    if (closed_ || aborted_)
      return;
    if (full_)
      ++dropped_;
    frame_ = std::move (frame);
    full_ = true;
  }
  ready_.notify_one ();
}

bool
LatestFrameSlot::take (SourceFrame &frame)
{
  std::unique_lock<std::mutex> lock (mutex_);
  ready_.wait (lock, [&] { return full_ || closed_ || aborted_; });
  if (aborted_)
    return false;
  if (full_)
  {
    frame = std::move (frame_);
    frame_ = SourceFrame ();
    full_ = false;
    return true;
  }
  if (error_)
    std::rethrow_exception (error_);  // every later take () says the same
  return false;
}

void
LatestFrameSlot::close (std::exception_ptr error)
{
  {
    std::lock_guard<std::mutex> lock (mutex_);
    if (!closed_)
      error_ = error;
    closed_ = true;
  }
  ready_.notify_all ();
}

void
LatestFrameSlot::abort ()
{
  {
    std::lock_guard<std::mutex> lock (mutex_);
    aborted_ = true;
    full_ = false;
    frame_ = SourceFrame ();
  }
  ready_.notify_all ();
}

std::uint64_t
LatestFrameSlot::dropped () const
{
  std::lock_guard<std::mutex> lock (mutex_);
  return dropped_;
}

// ---------------------------------------------------------------------------------------
namespace
{
bool
isFrameFile (const fs::path &path)
{
  std::string ext = path.extension ().string ();
  std::transform (ext.begin (), ext.end (), ext.begin (), [] (unsigned char c) { return std::tolower (c); });
  return ext == ".pcd" || ext == ".png" || ext == ".u16";
}

/** "<name of the directory holding the file>/<file name>", as agex_detect names frames. */
std::string
fileFrameName (const std::string &path)
{
  std::error_code ec;
  fs::path absolute = fs::weakly_canonical (fs::absolute (path, ec), ec);
  if (ec)
    absolute = fs::path (path).lexically_normal ();
  return absolute.parent_path ().filename ().string () + "/" + absolute.filename ().string ();
}

SourceFrame
loadSourceFrame (const std::string &path, const FrameOptions &options, std::uint64_t sequence)
{
  const Frame loaded = loadFrame (path, options);
  SourceFrame frame;
  frame.cloud = loaded.cloud;
  frame.intrinsics = loaded.intrinsics;
  frame.has_intrinsics = loaded.from_depth_image;
  frame.sequence = sequence;
  frame.name = fileFrameName (path);
  frame.path = path;
  return frame;
}

/** Frames read one by one from a list of files (files, directories, image sequences). */
class FileListSource : public FrameSource
{
public:
  FileListSource (std::vector<std::string> paths, const FrameOptions &options, std::string description)
    : paths_ (std::move (paths)), options_ (options), description_ (std::move (description))
  {
  }
  bool next (SourceFrame &frame) override
  {
    const std::size_t i = next_;
    if (stopped_ || i >= paths_.size ())
      return false;
    frame = loadSourceFrame (paths_[i], options_, i);
    ++next_;
    return true;
  }
  void stop () override { stopped_ = true; }
  std::string describe () const override { return description_; }

private:
  std::vector<std::string> paths_;
  FrameOptions options_;
  std::string description_;
  std::size_t next_ = 0;
  std::atomic<bool> stopped_{false};
};

/** An image sequence read until the first missing number. */
class ImageSequenceSource : public FrameSource
{
public:
  ImageSequenceSource (std::string pattern, const FrameOptions &options, int first)
    : pattern_ (std::move (pattern)), options_ (options), number_ (first)
  {
  }
  std::string pathOf (long long number) const
  {
    char buffer[4096];
    // The pattern was checked: one %d or %0Nd and nothing else but %%.
    const int n = std::snprintf (buffer, sizeof buffer, pattern_.c_str (), static_cast<int> (number));
    if (n < 0 || n >= static_cast<int> (sizeof buffer))
      throw FrameError (pattern_ + ": the image sequence's file names are too long");
    return buffer;
  }
  bool next (SourceFrame &frame) override
  {
    if (stopped_ || number_ > kLastNumber)
      return false;
    const std::string path = pathOf (number_);
    std::error_code ec;
    if (!fs::exists (path, ec))
      return false;
    frame = loadSourceFrame (path, options_, sequence_);
    ++sequence_;
    ++number_;
    return true;
  }
  void stop () override { stopped_ = true; }
  std::string describe () const override { return "image sequence " + pattern_; }

  static constexpr long long kLastNumber = 999999999;

private:
  std::string pattern_;
  FrameOptions options_;
  long long number_;
  std::uint64_t sequence_ = 0;
  std::atomic<bool> stopped_{false};
};

class DatasetSource : public FrameSource
{
public:
  explicit DatasetSource (Dataset dataset) : dataset_ (std::move (dataset))
  {
    std::error_code ec;
    fs::path dir = fs::weakly_canonical (fs::absolute (dataset_.directory (), ec), ec);
    root_ = (ec ? fs::path (dataset_.directory ()).lexically_normal () : dir).filename ().string ();
  }
  bool next (SourceFrame &frame) override
  {
    const std::size_t i = next_;
    if (stopped_ || i >= dataset_.frames ().size ())
      return false;
    const std::string &id = dataset_.frames ()[i].id;
    frame = SourceFrame ();
    frame.cloud = dataset_.loadFrame (id);
    frame.intrinsics = dataset_.info ().intrinsics;
    frame.has_intrinsics = dataset_.info ().intrinsics.fx > 0.0 && dataset_.info ().intrinsics.fy > 0.0;
    frame.sequence = i;
    frame.name = root_ + "/" + id;
    frame.path = dataset_.framePath (id);
    ++next_;
    return true;
  }
  void stop () override { stopped_ = true; }
  std::string describe () const override
  {
    return "dataset " + dataset_.directory () + " (" + std::to_string (dataset_.frames ().size ()) + " frames)";
  }

private:
  Dataset dataset_;
  std::string root_;
  std::size_t next_ = 0;
  std::atomic<bool> stopped_{false};
};

/** Another source offered at a fixed rate through a LatestFrameSlot. */
class ReplaySource : public FrameSource
{
public:
  ReplaySource (FrameSource::Ptr source, double fps) : source_ (std::move (source)), fps_ (fps)
  {
    producer_ = std::thread ([this] { produce (); });
  }
  ~ReplaySource () override
  {
    stop ();
    producer_.join ();
  }
  bool next (SourceFrame &frame) override { return slot_.take (frame); }
  void stop () override
  {
    {
      std::lock_guard<std::mutex> lock (mutex_);
      stopped_ = true;
    }
    wake_.notify_all ();
    slot_.abort ();
  }
  bool live () const override { return true; }
  std::uint64_t dropped () const override { return slot_.dropped (); }
  std::string describe () const override
  {
    std::ostringstream text;
    text << source_->describe () << " replayed at " << fps_ << " fps";
    return text.str ();
  }

private:
  void produce ()
  {
    using clock = std::chrono::steady_clock;
    const auto start = clock::now ();
    try
    {
      for (std::uint64_t i = 0;; ++i)
      {
        const auto due = start + std::chrono::duration_cast<clock::duration> (std::chrono::duration<double> (i / fps_));
        {
          std::unique_lock<std::mutex> lock (mutex_);
          if (wake_.wait_until (lock, due, [&] { return stopped_; }))
            return;
        }
        SourceFrame frame;
        if (!source_->next (frame))
          break;
        frame.sequence = i;
        frame.timestamp = i / fps_;
        slot_.put (std::move (frame));
      }
      slot_.close ();
    }
    catch (...)
    {
      slot_.close (std::current_exception ());
    }
  }

  FrameSource::Ptr source_;
  double fps_;
  LatestFrameSlot slot_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopped_ = false;
  std::thread producer_;
};

/** Checks an image sequence pattern: exactly one %d or %0Nd (N <= 9), otherwise only %%. */
void
checkSequencePattern (const std::string &pattern)
{
  int conversions = 0;
  for (std::size_t i = 0; i < pattern.size (); ++i)
  {
    if (pattern[i] != '%')
      continue;
    if (i + 1 < pattern.size () && pattern[i + 1] == '%')
    {
      ++i;
      continue;
    }
    std::size_t j = i + 1;
    if (j < pattern.size () && pattern[j] == '0')
    {
      ++j;
      if (j < pattern.size () && pattern[j] >= '1' && pattern[j] <= '9')
        ++j;
      else
        j = pattern.size ();  // "%0" must be followed by a width
    }
    if (j >= pattern.size () || pattern[j] != 'd')
      throw FrameError (pattern + ": an image sequence pattern takes one %d or %0Nd (N at most 9) and %% for a "
                                  "literal %; '" + pattern.substr (i, std::min<std::size_t> (4, pattern.size () - i)) +
                        "' is neither");
    ++conversions;
    i = j;
  }
  if (conversions != 1)
    throw FrameError (pattern + ": an image sequence pattern needs exactly one frame number (%d or %0Nd), it has " +
                      std::to_string (conversions));
}
}  // namespace

// ---------------------------------------------------------------------------------------
FrameSource::Ptr
openFrameFiles (const std::vector<std::string> &paths, const FrameOptions &options)
{
  if (paths.empty ())
    throw FrameError ("no frame files given");
  const std::string what = paths.size () == 1 ? "frame " + paths[0] : std::to_string (paths.size ()) + " frame files";
  return std::make_unique<FileListSource> (paths, options, what);
}

FrameSource::Ptr
openFrameDirectory (const std::string &directory, const FrameOptions &options)
{
  std::error_code ec;
  if (!fs::is_directory (directory, ec))
    throw FrameError (directory + ": no such directory");
  std::vector<std::string> files;
  for (const auto &entry : fs::directory_iterator (directory, ec))
    if (entry.is_regular_file () && isFrameFile (entry.path ()))
      files.push_back (entry.path ().string ());
  if (ec)
    throw FrameError (directory + ": cannot list: " + ec.message ());
  if (files.empty ())
    throw FrameError (directory + ": no frames (.pcd, .png, .u16) in this directory");
  std::sort (files.begin (), files.end ());
  const std::string what = "directory " + directory + " (" + std::to_string (files.size ()) + " frames)";
  return std::make_unique<FileListSource> (std::move (files), options, what);
}

FrameSource::Ptr
openDatasetFrames (const std::string &directory)
{
  return std::make_unique<DatasetSource> (Dataset::read (directory));
}

FrameSource::Ptr
openImageSequence (const std::string &pattern, const FrameOptions &options, int first)
{
  checkSequencePattern (pattern);
  if (first < 0)
    throw FrameError (pattern + ": an image sequence starts at a frame number of 0 or more");
  auto source = std::make_unique<ImageSequenceSource> (pattern, options, first);
  const std::string path = source->pathOf (first);
  std::error_code ec;
  if (!fs::exists (path, ec))
    throw FrameError (pattern + ": the image sequence's first frame " + path + " does not exist");
  return source;
}

FrameSource::Ptr
openFrames (const std::string &spec, const FrameOptions &options)
{
  std::error_code ec;
  if (fs::is_directory (spec, ec) && fs::exists (fs::path (spec) / "dataset.json", ec))
    return openDatasetFrames (spec);
  if (fs::is_directory (spec, ec))
    return openFrameDirectory (spec, options);
  if (!fs::exists (spec, ec) && spec.find ('%') != std::string::npos)
    return openImageSequence (spec, options);
  if (!fs::exists (spec, ec))
    throw FrameError (spec + ": no such file or directory (frames: a file, a directory, a dataset or an image "
                             "sequence pattern with %d)");
  return openFrameFiles ({spec}, options);
}

FrameSource::Ptr
replayAtRate (FrameSource::Ptr source, double fps)
{
  if (!source)
    throw std::invalid_argument ("replayAtRate needs a source");
  // Slower than one frame in ten seconds is a stalled stream, not a replay; so slow a rate
  // also overflowed the schedule's clock (1e-10 ran at full speed, 1e-9 waited 31 years).
  if (!(fps >= kMinReplayFps && fps <= kMaxReplayFps))
    throw std::invalid_argument ("a replay's frame rate must lie in [0.1, 1000] frames per second");
  return std::make_unique<ReplaySource> (std::move (source), fps);
}
}  // namespace agex
