// agex_landmarks: people boxes and 180 body-contour landmarks per person in images, a
// video or a camera. Uses the bundled model and OpenCV's people detector unless told
// otherwise.

#include <agex/apps/command_line.h>
#include <agex/apps/landmarks.h>
#include <agex/apps/output.h>
#include <agex/io/atomic_file.h>

#include <boost/program_options.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <regex>
#include <chrono>
#include <csignal>
#include <iostream>

namespace po = boost::program_options;

namespace
{
double
msSince (std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double, std::milli> (std::chrono::steady_clock::now () - start).count ();
}

struct FrameResult
{
  std::vector<agex::apps::LandmarkedPerson> people;
  double detect_ms = 0, landmarks_ms = 0;
};

FrameResult
processFrame (const cv::Mat &image, const agex::PeopleDetector &detector, const agex::ContourShapePredictor &predictor,
              double threshold)
{
  FrameResult result;
  const cv::Mat grey = agex::toGrey (image);
  auto start = std::chrono::steady_clock::now ();
  const std::vector<agex::PersonDetection> detections = detector.detect (grey, threshold);
  result.detect_ms = msSince (start);
  start = std::chrono::steady_clock::now ();
  for (const agex::PersonDetection &d : detections)
    result.people.push_back ({d.box, d.score, predictor.predict (grey, d.box)});
  result.landmarks_ms = msSince (start);
  return result;
}

nlohmann::json
frameJson (const std::string &source, const FrameResult &result)
{
  nlohmann::json people = nlohmann::json::array ();
  for (const auto &person : result.people)
    people.push_back (agex::apps::landmarkedPersonJson (person));
  return {{"source", source}, {"people", people}, {"ms", {{"detect", result.detect_ms}, {"landmarks", result.landmarks_ms}}}};
}

/** Set by Ctrl-C: a camera runs until then, and what was seen is still written. */
volatile std::sig_atomic_t interrupted = 0;

void
stopReading (int)
{
  interrupted = 1;
  std::signal (SIGINT, SIG_DFL);  // a second Ctrl-C ends a read that blocks
}
// An image-sequence video (frames/f%03d.png) reads every file its pattern matches; the
// overlay must not be one of them.
void
checkNotInImageSequence (const std::string &overlay, const std::string &video)
{
  namespace fs = std::filesystem;
  if (video.find ('%') == std::string::npos)
    return;
  std::string pattern;
  const std::string name = fs::path (video).filename ().string ();
  for (std::size_t i = 0; i < name.size (); ++i)
  {
    std::size_t j = i + 1;
    while (name[i] == '%' && j < name.size () && std::isdigit (static_cast<unsigned char> (name[j])))
      ++j;
    if (name[i] == '%' && j < name.size () && name[j] == 'd')
    {
      pattern += "[0-9]+";
      i = j;
    }
    else
      pattern += std::isalnum (static_cast<unsigned char> (name[i])) ? std::string (1, name[i]) : "\\" + std::string (1, name[i]);
  }
  std::error_code ec;
  const fs::path out = fs::weakly_canonical (overlay, ec), dir = fs::weakly_canonical (fs::path (video).parent_path ().empty () ? "." : fs::path (video).parent_path (), ec);
  if (out.parent_path () == dir && std::regex_match (out.filename ().string (), std::regex (pattern)))
    throw std::runtime_error (overlay + ": output would overwrite a frame of the image sequence " + video +
                              "; choose another path");
}
}  // namespace

int
main (int argc, char **argv)
{
  std::vector<std::string> inputs;
  std::string model_path = AGEX_BUNDLED_LANDMARK_MODEL, detector_path, json_path, overlay_path, video;
  double threshold = 0.0, opencv_scale = 0.5;
  int max_frames = 0, repeat = 1;
  po::options_description general ("agex_landmarks INPUT... [options]\n"
                                   "People boxes and 180 body-contour landmarks per person");
  general.add_options () ("help,h", "show this help") ("input", po::value (&inputs)->multitoken (), "image files")
    ("model", po::value (&model_path)->default_value (model_path), "shape predictor (agex_landmarks_train)")
    ("detector", po::value (&detector_path), "people detector (default: OpenCV's HOG people detector)")
    ("opencv-scale", po::value (&opencv_scale)->default_value (opencv_scale),
     "without --detector: resize images by this before OpenCV's people detector (smaller: faster, misses "
     "people shorter than about 96/scale pixels)")
    ("threshold", po::value (&threshold)->default_value (threshold), "detection threshold (higher: fewer, surer people)")
    ("json", po::value (&json_path), "write boxes and landmarks as JSON here")
    ("overlay", po::value (&overlay_path), "write an overlay PNG here (the last image or frame)")
    ("video", po::value (&video), "a video file, or a camera number, processed frame by frame until its end, "
     "--max-frames or Ctrl-C (the outputs are written then)")
    ("max-frames", po::value (&max_frames)->default_value (0), "stop a video after this many frames (0: all)")
    ("repeat", po::value (&repeat)->default_value (repeat),
     "process each image N times and report the fastest run of each stage (timing on a busy machine)");
  po::positional_options_description positional;
  positional.add ("input", -1);
  try
  {
    if (!agex::apps::parseCommandLine (argc, argv, general, positional))
      return 0;
    if (inputs.empty () && video.empty ())
      throw std::runtime_error ("no INPUT image or --video given (see --help)");
    if (!(opencv_scale > 0.05 && opencv_scale <= 4.0))
      throw std::runtime_error ("--opencv-scale must lie in (0.05, 4]");
    if (!detector_path.empty () && opencv_scale != 0.5)
      throw std::runtime_error ("--opencv-scale applies to OpenCV's detector only, not to --detector");
    if (repeat < 1)
      throw std::runtime_error ("--repeat must be at least 1");
    if (max_frames < 0)
      throw std::runtime_error ("--max-frames must be 0 (all) or more");
    const bool camera = !video.empty () && std::all_of (video.begin (), video.end (), ::isdigit);
    if (camera && video.size () > 4)
      throw std::runtime_error ("--video " + video + ": no such camera number");
    if (!overlay_path.empty () && !camera)
      checkNotInImageSequence (overlay_path, video);
    std::vector<std::string> read = inputs;
    read.push_back (model_path);
    if (!video.empty ())
      read.push_back (video);
    for (const auto &out : {json_path, overlay_path})
      if (!out.empty ())
        agex::checkOutputIsNotInput (out, read);
    const agex::ContourShapePredictor predictor = agex::apps::loadContourModel (model_path);
    const agex::PeopleDetector detector =
      detector_path.empty () ? agex::PeopleDetector::openCvDefault (opencv_scale) : agex::PeopleDetector::load (detector_path);

    nlohmann::json frames = nlohmann::json::array ();
    cv::Mat last_image;
    FrameResult last;
    auto report = [&] (const std::string &source, const cv::Mat &image, FrameResult result) {
      std::cout << source << ": " << result.people.size () << " people, detect " << result.detect_ms << " ms, landmarks "
                << result.landmarks_ms << " ms\n";
      frames.push_back (frameJson (source, result));
      last_image = image;
      last = std::move (result);
    };
    for (const std::string &input : inputs)
    {
      const cv::Mat image = agex::apps::readImage (input, cv::IMREAD_COLOR);
      FrameResult best = processFrame (image, detector, predictor, threshold);
      for (int r = 1; r < repeat; ++r)
      {
        const FrameResult again = processFrame (image, detector, predictor, threshold);
        best.detect_ms = std::min (best.detect_ms, again.detect_ms);
        best.landmarks_ms = std::min (best.landmarks_ms, again.landmarks_ms);
      }
      report (input, image, std::move (best));
    }
    if (!video.empty ())
    {
      cv::VideoCapture capture;
      // OpenCV logs each backend that fails to open the input; the one error below says it.
      const auto log_level = cv::utils::logging::setLogLevel (cv::utils::logging::LOG_LEVEL_SILENT);
      const bool opened = camera ? capture.open (std::stoi (video)) : capture.open (video);
      cv::utils::logging::setLogLevel (log_level);
      if (!opened)
        throw std::runtime_error (video + ": cannot open the video or camera");
      std::signal (SIGINT, stopReading);
      cv::Mat frame;
      int n = 0;
      for (; !interrupted && (max_frames == 0 || n < max_frames) && capture.read (frame) && !frame.empty (); ++n)
        report (video + "#" + std::to_string (n), frame.clone (), processFrame (frame, detector, predictor, threshold));
      if (n == 0 && !interrupted)
        throw std::runtime_error (video + ": opened, but not a single frame could be read from it");
    }
    nlohmann::json doc = {{"model", model_path}, {"detector", detector.description ()}, {"frames", frames}};
    if (!json_path.empty ())
      agex::apps::writeJson (json_path, doc);
    if (!overlay_path.empty () && !last_image.empty ())
      agex::apps::writePng (overlay_path, agex::apps::renderLandmarkOverlay (last_image, last.people));
    return 0;
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_landmarks: error: " << e.what () << "\n";
    return 1;
  }
}
