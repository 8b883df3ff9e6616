#include <agex/apps/frame_jobs.h>

#include <agex/apps/command_line.h>
#include <agex/apps/dataset_selection.h>
#include <agex/io/dataset.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <filesystem>
#include <iostream>
#include <map>
#include <mutex>
#include <stdexcept>

namespace fs = std::filesystem;

namespace agex
{
namespace apps
{
namespace
{
bool
isFrameFile (const fs::path &path)
{
  std::string ext = path.extension ().string ();
  std::transform (ext.begin (), ext.end (), ext.begin (), [] (unsigned char c) { return std::tolower (c); });
  return ext == ".pcd" || ext == ".png" || ext == ".u16";
}

fs::path
canonical (const std::string &path)
{
  std::error_code ec;
  const fs::path p = fs::weakly_canonical (fs::absolute (path, ec), ec);
  return ec ? fs::path (path).lexically_normal () : p;
}
}  // namespace

std::vector<FrameJob>
collectFrameJobs (const std::vector<std::string> &inputs, InputFiles &read, const std::string &app)
{
  std::vector<FrameJob> jobs;
  std::map<std::string, std::string> file_of;  // canonical name -> canonical file
  auto add = [&] (const std::string &name, const std::string &path) {
    const std::string file = canonical (path).string ();
    const auto [it, inserted] = file_of.emplace (name, file);
    if (!inserted && it->second != file)
      throw std::runtime_error (path + ": has the same name '" + name + "' as " + it->second +
                                "; results are keyed by name, so give them in separate runs");
    if (inserted)
      jobs.push_back ({name, path});
    read.add (path);
  };
  for (const auto &input : inputs)
  {
    const std::size_t before = jobs.size ();
    std::error_code ec;
    if (fs::is_directory (input, ec) && fs::exists (fs::path (input) / "dataset.json", ec))
    {
      const Dataset dataset = Dataset::read (input);
      read.addTree (input);
      for (const auto &file : datasetFiles (dataset))
        read.add (file);
      const std::string root = canonical (input).filename ().string ();
      for (const auto &frame : dataset.frames ())
        add (root + "/" + frame.id, dataset.framePath (frame.id));
    }
    else if (fs::is_directory (input, ec))
    {
      std::vector<std::string> files;
      for (const auto &entry : fs::directory_iterator (input))
        if (entry.is_regular_file () && isFrameFile (entry.path ()))
          files.push_back (entry.path ().string ());
      if (files.empty ())
        throw std::runtime_error (input + ": no frames (.pcd, .png, .u16) in this directory");
      std::sort (files.begin (), files.end ());
      const std::string root = canonical (input).filename ().string ();
      for (const auto &f : files)
        add (root + "/" + fs::path (f).filename ().string (), f);
    }
    else if (fs::exists (input, ec))
    {
      // A frame of a dataset is that dataset's frame, whichever way it is given.
      const std::string dataset = enclosingDataset (input);
      if (!dataset.empty ())
      {
        read.addTree (dataset);
        add (fs::path (dataset).filename ().string () + "/" + fs::path (input).stem ().string (), input);
      }
      else
        add (canonical (input).parent_path ().filename ().string () + "/" + fs::path (input).filename ().string (),
             input);
    }
    else
      throw std::runtime_error (input + ": no such file or directory");
    if (jobs.size () == before && !fs::is_directory (input, ec))
      std::cerr << app << ": " << input << " is given twice; processed once\n";
  }
  return jobs;
}

void
runFrameBatch (const std::vector<FrameJob> &jobs, ResultsFile *results, int threads,
               const std::function<nlohmann::json (const FrameJob &)> &process)
{
  std::vector<const FrameJob *> todo;
  for (const auto &j : jobs)
    if (!results || !results->contains (j.name))
      todo.push_back (&j);
  if (results && results->doneCount () > 0)
    std::cerr << results->app () << ": " << results->doneCount () << " frames already in " << results->path ()
              << ", " << todo.size () << " to go\n";
  std::mutex mutex;
  std::atomic<std::size_t> next{0}, finished{0};
  std::atomic<bool> failed{false};
  std::string first_error;
  Progress progress ("frames", todo.size ());
  auto worker = [&] () {
    // After a failure no new frame is started; those in flight finish.
    for (std::size_t i = next++; i < todo.size () && !failed; i = next++)
    {
      std::string line;
      try
      {
        line = process (*todo[i]).dump ();
        if (results)
          results->append (line);
      }
      catch (const std::exception &e)
      {
        std::lock_guard<std::mutex> lock (mutex);
        if (first_error.empty ())
          first_error = e.what ();
        failed = true;
        continue;
      }
      std::lock_guard<std::mutex> lock (mutex);
      if (!results)
        std::cout << line << "\n" << std::flush;
      progress.step (++finished);
    }
  };
  runWorkers (threads, todo.size (), worker);
  if (!first_error.empty ())
    throw std::runtime_error (first_error + (results && (finished > 0 || results->doneCount () > 0)
                                                 ? " (the frames done are kept in " + results->path () +
                                                       "; fix or remove that frame and rerun to go on)"
                                                 : std::string ()));
}
}  // namespace apps
}  // namespace agex
