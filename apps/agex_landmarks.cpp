// agex_landmarks: people boxes and 180 body-contour landmarks per person in images, a
// video or a camera. Uses the bundled people detector and shape predictor unless told
// otherwise (OpenCV's people detector only when asked).

#include <agex/apps/command_line.h>
#include <agex/apps/landmarks.h>
#include <agex/landmarks/image_files.h>
#include <agex/landmarks/people_landmarks.h>

#include <boost/program_options.hpp>
#include <opencv2/imgcodecs.hpp>

#include <iostream>

namespace po = boost::program_options;

int
main (int argc, char **argv)
{
  std::vector<std::string> inputs;
  std::string model_path = AGEX_BUNDLED_LANDMARK_MODEL, json_path, lines_path, overlay_path, video;
  agex::apps::PeopleDetectorChoice detector_choice;
  double threshold = 0.0;
  int max_frames = 0, repeat = 1;
  po::options_description options ("agex_landmarks INPUT... [options]\nPeople boxes and 180 body-contour landmarks per person");
  options.add_options () ("help,h", "show this help") ("input", po::value (&inputs)->multitoken (), "image files")
    ("model", po::value (&model_path)->default_value (model_path), "shape predictor (agex_landmarks_train)")
    ("threshold", po::value (&threshold)->default_value (threshold), "detection threshold (higher: fewer, surer people)")
    ("json", po::value (&json_path), "write boxes and landmarks of every image or frame as one JSON document here")
    ("json-lines", po::value (&lines_path), "write one JSON line per image or frame here ('-': standard output, "
     "as each frame is done)")
    ("overlay", po::value (&overlay_path), "write an overlay PNG here (the last image or frame)")
    ("video", po::value (&video), "a video file, an image sequence (frames/f%04d.png) or a camera number, processed frame by frame until its end, "
     "--max-frames or Ctrl-C (the outputs are written then)")
    ("max-frames", po::value (&max_frames)->default_value (0), "stop a video after this many frames (0: all)")
    ("repeat", po::value (&repeat)->default_value (repeat),
     "process each image N times and report the fastest run of each stage (timing on a busy machine)");
  options.add (agex::apps::detectorChoiceOptions (detector_choice));
  po::positional_options_description positional;
  positional.add ("input", -1);
  try
  {
    if (!agex::apps::parseCommandLine (argc, argv, options, positional))
      return 0;
    if (inputs.empty () && video.empty ())
      throw std::runtime_error ("no INPUT image or --video given (see --help)");
    if (repeat < 1 || max_frames < 0)
      throw std::runtime_error ("--repeat must be at least 1, --max-frames 0 (all) or more");
    const std::string lines_file = lines_path == "-" ? "" : lines_path;  // "-": standard output
    agex::apps::checkLandmarkOutputs (json_path, lines_file, overlay_path, inputs, model_path, video);
    const agex::ContourShapePredictor predictor = agex::loadContourModel (model_path);
    const agex::PeopleDetector detector = agex::apps::loadPeopleDetector (detector_choice);

    agex::apps::LandmarkOutputs outputs (lines_path == "-");
    for (const std::string &input : inputs)
    {
      const cv::Mat image = agex::readImage (input, cv::IMREAD_COLOR);
      outputs.add (input, image, agex::apps::landmarkPeopleFastest (image, detector, predictor, threshold, repeat));
    }
    if (!video.empty ())
      agex::apps::readVideo (video, max_frames, [&] (const std::string &source, const cv::Mat &frame) {
        outputs.add (source, frame.clone (), agex::landmarkPeople (frame, detector, predictor, threshold));
      });
    outputs.write ({{"model", model_path}, {"detector", detector.description ()}}, json_path, lines_file, overlay_path);
    return 0;
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_landmarks: error: " << e.what () << "\n";
    return 1;
  }
}
