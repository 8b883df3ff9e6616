// agex_detect: heads, hands and feet in depth frames.
//   agex_detect INPUT... [--model MODEL] [--json FILE] [--overlay FILE.png] [--jobs N]
// INPUT is a frame file, a directory of frames or an agex dataset. One frame: a JSON
// document. Several: JSON lines, one per frame, written as they finish, in parallel
// with --jobs; a rerun with the same --json skips the frames already there.

#include <agex/apps/command_line.h>
#include <agex/apps/dataset_selection.h>
#include <agex/apps/pipeline_flags.h>
#include <agex/detection/depth_pipeline.h>
#include <agex/apps/output.h>
#include <agex/detection/body_part_detector.h>
#include <agex/io/atomic_file.h>
#include <agex/io/dataset.h>
#include <agex/io/frame_io.h>

#include <boost/program_options.hpp>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <mutex>
#include <set>
#include <cstring>
#include <thread>

#include <fcntl.h>
#include <unistd.h>

namespace fs = std::filesystem;
namespace po = boost::program_options;

namespace
{
struct Job
{
  std::string name;  ///< frame path, or dataset/id
  std::string path;  ///< file to load
};

bool
isFrameFile (const fs::path &path)
{
  std::string ext = path.extension ().string ();
  std::transform (ext.begin (), ext.end (), ext.begin (), [] (unsigned char c) { return std::tolower (c); });
  return ext == ".pcd" || ext == ".png" || ext == ".u16";
}

/** The frames to process, each once, named by its normalised path (so that "d", "./d" and
  * "d/" name the same frames on a rerun); read gets every file they come from. */
std::vector<Job>
collectJobs (const std::vector<std::string> &inputs, agex::InputFiles &read)
{
  std::vector<Job> jobs;
  std::set<std::string> named;
  auto add = [&] (const fs::path &name, const std::string &path) {
    const std::string normal = name.lexically_normal ().string ();
    if (named.insert (normal).second)
      jobs.push_back ({normal, path});
    read.add (path);
  };
  for (const auto &input : inputs)
  {
    const std::size_t before = jobs.size ();
    if (fs::is_directory (input) && fs::exists (fs::path (input) / "dataset.json"))
    {
      const agex::Dataset dataset = agex::Dataset::read (input);
      for (const auto &file : agex::apps::datasetFiles (dataset))
        read.add (file);
      for (const auto &frame : dataset.frames ())
        add (fs::path (input) / frame.id, dataset.framePath (frame.id));
    }
    else if (fs::is_directory (input))
    {
      std::vector<std::string> files;
      for (const auto &entry : fs::directory_iterator (input))
        if (entry.is_regular_file () && isFrameFile (entry.path ()))
          files.push_back (entry.path ().string ());
      std::sort (files.begin (), files.end ());
      for (const auto &f : files)
        add (f, f);
      if (files.empty ())
        throw std::runtime_error (input + ": no frames (.pcd, .png, .u16) in this directory");
    }
    else if (fs::exists (input))
      add (input, input);
    else
      throw std::runtime_error (input + ": no such file or directory");
    if (jobs.size () == before && !fs::is_directory (input))
      std::cerr << "agex_detect: " << input << " is given twice; processed once\n";
  }
  return jobs;
}

/** Frames already in a JSON-lines file of an earlier run. Only the last line may be torn
  * (a run interrupted while writing it): it is dropped, and a missing final newline added,
  * by rewriting the file atomically. Anything else that is not one of our lines means the
  * file is not ours, and it is left alone. */
std::set<std::string>
framesDone (const std::string &path)
{
  std::set<std::string> done;
  std::ifstream in (path, std::ios::binary);
  if (!in)
    return done;
  const std::string content ((std::istreambuf_iterator<char> (in)), std::istreambuf_iterator<char> ());
  std::string kept;
  std::size_t line_number = 0;
  bool rewrite = false;
  for (std::size_t begin = 0; begin < content.size ();)
  {
    std::size_t end = content.find ('\n', begin);
    const bool last = end == std::string::npos;
    if (last)
      end = content.size ();
    const std::string line = content.substr (begin, end - begin);
    begin = end + 1;
    ++line_number;
    if (line.empty ())
      continue;
    try
    {
      const auto doc = nlohmann::json::parse (line);
      done.insert (doc.at ("frame").get<std::string> ());
      kept += line + "\n";
      rewrite = rewrite || last;  // the final newline was missing
    }
    catch (const std::exception &)
    {
      // Our lines are JSON objects: a torn one still starts like one.
      if (!last || line[0] != '{')
        throw std::runtime_error (path + ": line " + std::to_string (line_number) +
                                  " is not a frame result of agex_detect; --json of several frames appends "
                                  "to a JSON-lines file: choose a new path or that of an earlier such run");
      rewrite = true;  // torn by an interrupted run
    }
  }
  if (rewrite)
    agex::writeFileAtomic (path, kept);
  return done;
}

cv::Mat
renderDetections (const agex::DepthPipelineResult &prepared, const pcl::PointCloud<pcl::PointXYZ> &frame,
                  const std::vector<agex::BodyPartDetection> &detections, float min_confidence)
{
  cv::Mat image = agex::apps::renderOverlay (frame, prepared.meshes, pcl::PointCloud<agex::InterestPoint> ());
  const int scale = std::max (1, image.rows / static_cast<int> (std::max (1u, frame.height)));
  for (auto it = detections.rbegin (); it != detections.rend (); ++it)  // most confident drawn last
  {
    if (it->confidence < min_confidence)
      continue;
    const cv::Point centre ((it->u + 0.5) * scale, (it->v + 0.5) * scale);
    const cv::Scalar colour = agex::apps::bodyPartColour (static_cast<int> (it->part));
    const cv::Point tip = centre + cv::Point (static_cast<int> (std::lround (it->orientation.x () * 40)),
                                              static_cast<int> (std::lround (it->orientation.y () * 40)));
    if (tip != centre)
      cv::arrowedLine (image, centre, tip, colour, 2, cv::LINE_AA, 0, 0.3);
    cv::circle (image, centre, 9, colour, 3, cv::LINE_AA);
    char text[64];
    std::snprintf (text, sizeof text, "%s %.2f", agex::bodyPartName (it->part), it->confidence);
    cv::putText (image, text, centre + cv::Point (12, -8), cv::FONT_HERSHEY_SIMPLEX, 0.55, cv::Scalar (0, 0, 0), 3,
                 cv::LINE_AA);
    cv::putText (image, text, centre + cv::Point (12, -8), cv::FONT_HERSHEY_SIMPLEX, 0.55, colour, 1, cv::LINE_AA);
  }
  return image;
}
}  // namespace

int
main (int argc, char **argv)
{
  agex::FrameOptions frame_options;
  std::vector<std::string> inputs;
  std::string model_path = AGEX_BUNDLED_MODEL, json_path, overlay_path;
  int jobs = 1;
  float min_confidence = 0.5f;

  po::options_description general ("agex_detect INPUT... [options]\n"
                                    "Heads, hands and feet in depth frames (.pcd, .png, .u16, directories, datasets)");
  general.add_options () ("help,h", "show this help") ("input", po::value (&inputs)->multitoken (), "inputs")
    ("model", po::value (&model_path)->default_value (model_path), "model file (default: the bundled model)")
    ("json", po::value (&json_path), "one frame: JSON document; several: JSON lines, one per frame (resumable)")
    ("overlay", po::value (&overlay_path), "overlay PNG (one frame only)")
    ("min-confidence", po::value (&min_confidence)->default_value (min_confidence, "0.5"),
     "detections drawn on the overlay and printed")
    ("jobs", po::value (&jobs)->default_value (jobs), "frames processed in parallel");
  po::options_description all;
  all.add (general).add (agex::apps::frameOptionsDescription (frame_options));
  po::positional_options_description positional;
  positional.add ("input", -1);

  try
  {
    if (!agex::apps::parseCommandLine (argc, argv, all, positional))
      return 0;
    if (inputs.empty ())
      throw std::runtime_error ("no INPUT given (see --help)");
    if (jobs < 1)
      throw std::runtime_error ("--jobs must be at least 1");
    const auto model = std::make_shared<const agex::DetectorModel> (agex::DetectorModel::load (model_path));
    model->requireKind (agex::DetectorKind::Agex, model_path);
    agex::InputFiles read ({model_path});
    const std::vector<Job> job_list = collectJobs (inputs, read);
    for (const auto &out : {json_path, overlay_path})
      if (!out.empty ())
        read.checkOutput (out);

    auto process = [&] (const Job &job, nlohmann::json &doc, cv::Mat *overlay) {
      const auto start = std::chrono::steady_clock::now ();
      const agex::Frame frame = agex::loadFrame (job.path, frame_options);
      agex::BodyPartDetector<pcl::PointXYZ> detector;
      detector.setModel (model);
      detector.setInputCloud (frame.cloud);
      std::vector<agex::BodyPartDetection> detections;
      detector.compute (detections);
      const agex::DepthPipelineResult &prepared = detector.getIntermediate ();
      doc = {{"frame", job.name}, {"width", frame.cloud->width}, {"height", frame.cloud->height},
             {"detections", nlohmann::json::array ()}};
      for (const auto &d : detections)
        doc["detections"].push_back (agex::toJson (d));
      doc["ms"] = nlohmann::json::object ();
      for (const auto &[stage, ms] : prepared.ms)
        if (stage != "total")
          doc["ms"][stage] = ms;
      doc["ms"]["total"] = std::chrono::duration<double, std::milli> (std::chrono::steady_clock::now () - start).count ();
      if (overlay)
        *overlay = renderDetections (prepared, *frame.cloud, detections, min_confidence);
    };

    if (inputs.size () == 1 && fs::is_regular_file (inputs[0]))
    {
      nlohmann::json doc;
      cv::Mat overlay;
      process (job_list[0], doc, overlay_path.empty () ? nullptr : &overlay);
      if (!json_path.empty ())
        agex::apps::writeJson (json_path, doc);
      else
        std::cout << doc.dump (2) << "\n";
      if (!overlay_path.empty ())
        agex::apps::writePng (overlay_path, overlay);
      for (const auto &d : doc["detections"])
        if (d["confidence"].get<float> () >= min_confidence)
          std::cerr << "  " << d["class"].get<std::string> () << " " << d["confidence"].get<float> () << " at pixel ("
                    << d["pixel"][0] << ", " << d["pixel"][1] << ")\n";
      return 0;
    }

    if (!overlay_path.empty ())
      throw std::runtime_error ("--overlay takes a single frame");
    const std::set<std::string> done = json_path.empty () ? std::set<std::string> () : framesDone (json_path);
    std::vector<const Job *> todo;
    for (const auto &j : job_list)
      if (!done.count (j.name))
        todo.push_back (&j);
    if (!done.empty ())
      std::cerr << "agex_detect: " << done.size () << " frames already in " << json_path << ", " << todo.size ()
                << " to go\n";
    int fd = 1;
    if (!json_path.empty ())
    {
      fd = ::open (json_path.c_str (), O_WRONLY | O_CREAT | O_APPEND, 0644);
      if (fd < 0)
        throw std::runtime_error (json_path + ": cannot open for appending: " + std::strerror (errno));
    }
    std::mutex output_mutex;
    std::atomic<std::size_t> next{0}, finished{0};
    std::string first_error;
    agex::apps::Progress progress ("frames", todo.size ());
    std::atomic<bool> failed{false};
    auto worker = [&] () {
      // After a failure no new frame is started; those in flight finish.
      for (std::size_t i = next++; i < todo.size () && !failed; i = next++)
      {
        nlohmann::json doc;
        try
        {
          process (*todo[i], doc, nullptr);
        }
        catch (const std::exception &e)
        {
          std::lock_guard<std::mutex> lock (output_mutex);
          if (first_error.empty ())
            first_error = e.what ();
          failed = true;
          continue;
        }
        // One write per line: lines of parallel workers never interleave.
        const std::string line = doc.dump () + "\n";
        std::lock_guard<std::mutex> lock (output_mutex);
        if (::write (fd, line.data (), line.size ()) != static_cast<ssize_t> (line.size ()) && first_error.empty ())
          first_error = json_path + ": write failed";
        progress.step (++finished);
      }
    };
    agex::apps::runWorkers (jobs, todo.size (), worker);
    if (fd != 1)
      ::close (fd);
    if (!first_error.empty ())
      throw std::runtime_error (first_error + (json_path.empty () ? std::string ()
                                                                  : " (the frames done are kept in " + json_path +
                                                                      "; fix or remove that frame and rerun to go on)"));
    return 0;
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_detect: error: " << e.what () << "\n";
    return 1;
  }
}
