// The 2D landmark apps run as built: agex_annotate on COCO files (../shared and hand-made RLE
// masks), mask folders and RGB-D frames; agex_landmarks on the bundled image, a video and bad
// inputs; agex_landmarks_eval's report; and the datasets the apps load (partly annotated boxes).

#include <agex/apps/landmarks.h>
#include <agex/landmarks/contour_annotation.h>
#include <agex/landmarks/imglab_dataset.h>
#include <agex/landmarks/person_masks.h>

#include "landmarks/figures.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>

#include <sys/wait.h>

namespace
{
using agex_test::readAll;
using agex_test::writeAll;
using namespace landmark_test;  // drawFigure, Figure, tempDir
namespace fs = std::filesystem;

int
run (const std::string &command)
{
  return std::system ((command + " > /dev/null 2>&1").c_str ());
}

// A box with some but not all 180 landmarks names its line; boxes without any are kept out of
// training with a warning, not silently.
TEST (LandmarkApps, PartlyAnnotatedBoxesAreNamedByLine)
{
  const fs::path dir = tempDir ("partial_boxes");
  ASSERT_TRUE (cv::imwrite ((dir / "a.png").string (), cv::Mat (40, 30, CV_8UC1, cv::Scalar (50))));
  auto dataset = [&] (int parts) {
    agex::ImglabDataset d;
    agex::ImglabImage image;
    image.file = "a.png";
    agex::ImglabBox box;
    box.rect = cv::Rect (2, 3, 20, 30);
    for (int i = 0; i < parts; ++i)
      box.parts[agex::contourLandmarkName (i)] = cv::Point2f (5.f + i % 10, 6.f + i / 10);
    image.boxes = {box, box};
    image.boxes[0].parts.clear ();
    d.images.push_back (image);
    const std::string path = (dir / ("d" + std::to_string (parts) + ".xml")).string ();
    agex::writeImglabDataset (path, d);
    return path;
  };
  const std::string partial = dataset (179);
  try
  {
    agex::apps::loadLandmarkDatasets ({partial});
    ADD_FAILURE () << "a box with 179 landmarks was accepted";
  }
  catch (const std::runtime_error &e)
  {
    // The second <box> of the file.
    const std::string xml = readAll (partial);
    const std::size_t second_box = xml.find ("<box", xml.find ("<box") + 1);
    const long line = 1 + std::count (xml.begin (), xml.begin () + static_cast<long> (second_box), '\n');
    EXPECT_NE (std::string (e.what ()).find (partial + ": line " + std::to_string (line) + ": a box in a.png has 179 of the 180"),
               std::string::npos)
      << e.what ();
  }
  testing::internal::CaptureStderr ();
  const auto images = agex::apps::loadLandmarkDatasets ({dataset (180)});
  const std::string warning = testing::internal::GetCapturedStderr ();
  ASSERT_EQ (images.size (), 1u);
  EXPECT_EQ (images[0].people.size (), 1u);
  EXPECT_EQ (images[0].ignored.size (), 1u);
  EXPECT_NE (warning.find ("1 box(es) without contour landmarks"), std::string::npos) << warning;
  fs::remove_all (dir);
}

TEST (LandmarkApps, AnnotateCocoPeople)
{
  const std::string json = agex_test::sharedData ("people2d/coco/test_coco.json");
  AGEX_REQUIRE_SHARED_FILE (json, "the COCO people of ../shared/data/people2d");
  const fs::path dir = tempDir ("coco");
  const std::string xml = (dir / "coco.xml").string ();
  ASSERT_EQ (run (std::string (AGEX_ANNOTATE_EXECUTABLE) + " coco --json " + json + " --images " +
                  agex_test::sharedData ("people2d/coco") + " --out " + xml),
             0);
  const agex::ImglabDataset d = agex::readImglabDataset (xml);
  ASSERT_EQ (d.images.size (), 4u);
  int people = 0, ignored = 0;
  for (const auto &image : d.images)
  {
    EXPECT_TRUE (fs::exists (agex::resolveImglabImagePath (xml, image.file))) << image.file;
    for (const auto &box : image.boxes)
    {
      if (box.ignore)
      {
        ++ignored;
        continue;
      }
      ++people;
      int landmarks = 0;
      for (const auto &[name, p] : box.parts)
        if (agex::contourLandmarkIndex (name) >= 0)
        {
          ++landmarks;
          EXPECT_TRUE (cv::Rect (box.rect.x - 1, box.rect.y - 1, box.rect.width + 2, box.rect.height + 2).contains (p));
        }
      EXPECT_EQ (landmarks, 180);
    }
  }
  EXPECT_GE (people, 10);
  EXPECT_EQ (people + ignored, 14);
  // Bad input: a missing JSON is named.
  EXPECT_NE (run (std::string (AGEX_ANNOTATE_EXECUTABLE) + " coco --json " + (dir / "none.json").string () +
                  " --images " + dir.string () + " --out " + xml),
             0);
  fs::remove_all (dir);
}

TEST (LandmarkApps, AnnotateRgbdFrame)
{
  const std::string pcd = agex_test::sharedData ("kinect/five_people.pcd");
  AGEX_REQUIRE_SHARED_FILE (pcd, "the RGB-D frame of ../shared/data/kinect");
  const fs::path dir = tempDir ("rgbd");
  const std::string xml = (dir / "rgbd.xml").string ();
  ASSERT_EQ (run (std::string (AGEX_ANNOTATE_EXECUTABLE) + " rgbd " + pcd + " --out " + xml), 0);
  const agex::ImglabDataset d = agex::readImglabDataset (xml);
  ASSERT_EQ (d.images.size (), 1u);
  const cv::Mat colour = cv::imread (agex::resolveImglabImagePath (xml, d.images[0].file));
  EXPECT_EQ (colour.size (), cv::Size (640, 480));
  int people = 0;
  for (const auto &box : d.images[0].boxes)
    if (!box.ignore)
    {
      ++people;
      EXPECT_EQ (box.parts.size (), 180u);
      // A standing person: the head top is the highest landmark region, the feet low.
      EXPECT_LT (box.parts.at ("000").y, box.parts.at ("072").y);
      EXPECT_LT (box.parts.at ("000").y, box.parts.at ("108").y);
    }
  EXPECT_EQ (people, 5);  // the five people walking away
  // A working density would draw the masks on a coarser grid than the colour image: refused,
  // and the dataset written above stays.
  const std::string err = (dir / "err.txt").string ();
  EXPECT_NE (std::system ((std::string (AGEX_ANNOTATE_EXECUTABLE) + " rgbd " + pcd + " --out " + xml +
                           " --working-spacing 0.01 > /dev/null 2> " + err)
                              .c_str ()),
             0);
  std::ifstream in (err);
  const std::string message ((std::istreambuf_iterator<char> (in)), std::istreambuf_iterator<char> ());
  EXPECT_NE (message.find ("--working-spacing is not for annotation"), std::string::npos) << message;
  EXPECT_EQ (agex::readImglabDataset (xml).images.size (), 1u);
  fs::remove_all (dir);
}

TEST (LandmarkApps, BundledModelOnBundledImage)
{
  const std::string image = std::string (AGEX_SOURCE_DIR) + "/data/images/five_people.jpg";
  const fs::path dir = tempDir ("app");
  const std::string json = (dir / "out.json").string (), overlay = (dir / "out.png").string ();
  ASSERT_EQ (run (std::string (AGEX_LANDMARKS_EXECUTABLE) + " " + image + " --json " + json + " --overlay " + overlay), 0);
  const nlohmann::json doc = nlohmann::json::parse (readAll (json));
  ASSERT_EQ (doc["frames"].size (), 1u);
  for (const auto &person : doc["frames"][0]["people"])
    EXPECT_EQ (person["landmarks"].size (), 180u);
  EXPECT_FALSE (cv::imread (overlay).empty ());
  EXPECT_NE (run (std::string (AGEX_LANDMARKS_EXECUTABLE) + " " + (dir / "missing.png").string ()), 0);
  EXPECT_NE (run (std::string (AGEX_LANDMARKS_EXECUTABLE) + " " + image + " --model " + image), 0);
  fs::remove_all (dir);
}
TEST (LandmarkApps, BadImagesAndModelsAreNamedAndOutputsNeverLandOnInputs)
{
  const fs::path dir = tempDir ("bad_apps");
  const std::string app = AGEX_LANDMARKS_EXECUTABLE;
  auto exit_code = [] (const std::string &command) {
    const int status = std::system ((command + " > /dev/null 2>&1").c_str ());
    return WIFEXITED (status) ? WEXITSTATUS (status) : -1;  // -1: killed by a signal
  };
  const std::string good = std::string (AGEX_SOURCE_DIR) + "/data/images/five_people.jpg";
  const std::string jpeg = readAll (good), truncated = (dir / "truncated.jpg").string ();
  writeAll (truncated, jpeg.substr (0, jpeg.size () / 2));
  EXPECT_EQ (exit_code (app + " " + good), 0);
  // OpenCV would decode the first half with grey rows below it and a warning.
  EXPECT_EQ (exit_code (app + " " + truncated), 1);
  // Too small for the detector's window: no people, not an error.
  const std::string tiny = (dir / "tiny.png").string ();
  ASSERT_TRUE (cv::imwrite (tiny, cv::Mat (1, 1, CV_8UC3, cv::Scalar::all (90))));
  EXPECT_EQ (exit_code (app + " " + tiny + " --json " + (dir / "tiny.json").string ()), 0);
  // Damaged dlib models whose indices point outside the model, and one with 5 landmarks.
  for (const char *model : {"shape_predictor_bad_anchor.dat", "shape_predictor_bad_split.dat",
                            "shape_predictor_5_landmarks.dat"})
    EXPECT_EQ (exit_code (app + " " + good + " --model " + AGEX_SOURCE_DIR + "/test/bad_inputs/inputs/" + model), 1)
      << model;
  // An image-sequence video: the overlay may not replace one of its frames.
  std::vector<std::string> frames;
  for (int n = 0; n < 3; ++n)
  {
    frames.push_back ((dir / cv::format ("f%03d.png", n)).string ());
    ASSERT_TRUE (cv::imwrite (frames.back (), cv::Mat (64, 48, CV_8UC3, cv::Scalar::all (40 * n))));
  }
  const std::string before = readAll (frames[1]);
  EXPECT_EQ (exit_code (app + " --video " + (dir / "f%03d.png").string () + " --overlay " + frames[1]), 1);
  EXPECT_EQ (readAll (frames[1]), before);
  EXPECT_EQ (exit_code (app + " --video " + (dir / "f%03d.png").string () + " --overlay " +
                        (dir / "overlay.png").string ()),
             0);
  // A file that opens but yields no frame, and a camera number no camera has.
  writeAll ((dir / "notes.txt").string (), "not a video");
  EXPECT_EQ (exit_code (app + " --video " + (dir / "notes.txt").string ()), 1);
  EXPECT_EQ (exit_code (app + " --video 99999999999"), 1);
  fs::remove_all (dir);
}

TEST (LandmarkApps, AnnotationImagesAreStagedAndNeverOverwritten)
{
  const std::string pcd = agex_test::sharedData ("kinect/five_people.pcd");
  AGEX_REQUIRE_SHARED_FILE (pcd, "the RGB-D frame of ../shared/data/kinect");
  const fs::path dir = tempDir ("rgbd_names");
  // Two inputs of the same name (frames/000000.pcd of two agex_synth runs) get two images.
  for (const char *run_dir : {"a", "b"})
  {
    fs::create_directories (dir / run_dir);
    fs::copy_file (pcd, dir / run_dir / "frame.pcd");
  }
  const std::string a = (dir / "a" / "frame.pcd").string (), b = (dir / "b" / "frame.pcd").string ();
  const std::string xml = (dir / "out.xml").string ();
  ASSERT_EQ (run (std::string (AGEX_ANNOTATE_EXECUTABLE) + " rgbd " + a + " " + b + " --out " + xml), 0);
  const agex::ImglabDataset d = agex::readImglabDataset (xml);
  ASSERT_EQ (d.images.size (), 2u);
  EXPECT_NE (d.images[0].file, d.images[1].file);
  // A failing run (a damaged second input) leaves the earlier dataset's images as they were,
  // and no staging folder behind. (The marker stands for an earlier image: both inputs here
  // render the same picture.)
  const std::string image = agex::resolveImglabImagePath (xml, d.images[0].file), kept = "an earlier image";
  writeAll (image, kept);
  const std::string damaged = (dir / "damaged.pcd").string ();
  writeAll (damaged, readAll (pcd).substr (0, 3000));
  EXPECT_NE (run (std::string (AGEX_ANNOTATE_EXECUTABLE) + " rgbd " + b + " " + damaged + " --out " + xml), 0);
  EXPECT_EQ (readAll (image), kept);
  for (const auto &entry : fs::directory_iterator (fs::path (image).parent_path ()))
    EXPECT_EQ (entry.path ().filename ().string ().rfind (".agex_staging", 0), std::string::npos) << entry.path ();
  // Overlays may not land on the dataset's own images.
  EXPECT_NE (run (std::string (AGEX_ANNOTATE_EXECUTABLE) + " rgbd " + a + " --out " + xml + " --overlay-dir " +
                  fs::path (image).parent_path ().string ()),
             0);
  EXPECT_EQ (readAll (image), kept);
  fs::remove_all (dir);
}

TEST (LandmarkApps, VideoFileFrameByFrame)
{
  // A short MJPEG AVI written with OpenCV's own encoder (no FFmpeg needed): each of its
  // frames must give the people that the same decoded frame gives as a still image.
  const fs::path dir = tempDir ("video");
  const std::string video = (dir / "walk.avi").string ();
  const cv::Mat still = cv::imread (std::string (AGEX_SOURCE_DIR) + "/data/images/five_people.jpg");
  ASSERT_FALSE (still.empty ());
  {
    cv::VideoWriter writer (video, cv::CAP_OPENCV_MJPEG, cv::VideoWriter::fourcc ('M', 'J', 'P', 'G'), 10.0,
                            still.size ());
    ASSERT_TRUE (writer.isOpened ());
    cv::Mat shifted;
    for (int n = 0; n < 3; ++n)
    {
      // The people move 20 pixels to the right per frame.
      const cv::Mat shift = (cv::Mat_<double> (2, 3) << 1, 0, 20 * n, 0, 1, 0);
      cv::warpAffine (still, shifted, shift, still.size ());
      writer.write (shifted);
    }
  }
  std::vector<std::string> decoded;
  {
    cv::VideoCapture capture (video);  // the backend the app opens it with
    cv::Mat frame;
    while (capture.read (frame) && !frame.empty ())
    {
      decoded.push_back ((dir / ("frame" + std::to_string (decoded.size ()) + ".png")).string ());
      ASSERT_TRUE (cv::imwrite (decoded.back (), frame));
    }
  }
  ASSERT_EQ (decoded.size (), 3u);

  // OpenCV's detector finds these pedestrians seen from behind (the bundled one, trained on
  // frontal street-fashion photos, does not); the video path is the same for either.
  const std::string app = std::string (AGEX_LANDMARKS_EXECUTABLE) + " --opencv-detector";
  const std::string from_video = (dir / "video.json").string (), from_stills = (dir / "stills.json").string ();
  ASSERT_EQ (run (app + " --video " + video + " --json " + from_video), 0);
  std::string stills_command = app;
  for (const auto &frame : decoded)
    stills_command += " " + frame;
  ASSERT_EQ (run (stills_command + " --json " + from_stills), 0);
  const nlohmann::json v = nlohmann::json::parse (readAll (from_video));
  const nlohmann::json s = nlohmann::json::parse (readAll (from_stills));
  ASSERT_EQ (v["frames"].size (), 3u);
  std::size_t people = 0;
  for (std::size_t n = 0; n < 3; ++n)
  {
    EXPECT_EQ (v["frames"][n]["source"], video + "#" + std::to_string (n));
    ASSERT_EQ (v["frames"][n]["people"].size (), s["frames"][n]["people"].size ()) << "frame " << n;
    for (std::size_t i = 0; i < v["frames"][n]["people"].size (); ++i)
    {
      EXPECT_EQ (v["frames"][n]["people"][i]["box"], s["frames"][n]["people"][i]["box"]);
      EXPECT_EQ (v["frames"][n]["people"][i]["landmarks"].size (), 180u);
    }
    people += v["frames"][n]["people"].size ();
  }
  EXPECT_GT (people, 0u);

  // One JSON line per frame: into a file, and streamed on standard output as each frame is done.
  const std::string lines_path = (dir / "video.jsonl").string (), streamed = (dir / "streamed.jsonl").string ();
  ASSERT_EQ (run (app + " --video " + video + " --json-lines " + lines_path), 0);
  ASSERT_EQ (std::system ((app + " --video " + video + " --json-lines - > " + streamed +
                           " 2> /dev/null")
                            .c_str ()),
             0);
  for (const std::string &file : {lines_path, streamed})
  {
    std::istringstream in (readAll (file));
    std::string line;
    std::size_t n = 0;
    for (; std::getline (in, line); ++n)
    {
      const nlohmann::json frame = nlohmann::json::parse (line);
      EXPECT_EQ (frame["source"], video + "#" + std::to_string (n)) << file;
      ASSERT_LT (n, 3u) << file;
      EXPECT_EQ (frame["people"], v["frames"][n]["people"]) << file << " frame " << n;
    }
    EXPECT_EQ (n, 3u) << file;
  }

  // --max-frames stops early; a missing video and a file that is no video are refused.
  ASSERT_EQ (run (std::string (AGEX_LANDMARKS_EXECUTABLE) + " --video " + video + " --max-frames 2 --json " + from_video), 0);
  EXPECT_EQ (nlohmann::json::parse (readAll (from_video))["frames"].size (), 2u);
  EXPECT_NE (run (std::string (AGEX_LANDMARKS_EXECUTABLE) + " --video " + decoded[0] + "x --json " + from_video), 0);
  const std::string text = (dir / "notes.txt").string ();
  writeAll (text, "not a video\n");
  EXPECT_NE (run (std::string (AGEX_LANDMARKS_EXECUTABLE) + " --video " + text + " --json " + from_video), 0);
  fs::remove_all (dir);
}

// A palette PNG (colour type 3), as Penn-Fudan's PedMasks are: OpenCV cannot write one, and
// reads it back as the palette's colours. Stored (uncompressed) deflate blocks keep this short.
std::uint32_t
crc32Of (const std::string &bytes)
{
  std::uint32_t crc = 0xFFFFFFFFu;
  for (const unsigned char c : bytes)
  {
    crc ^= c;
    for (int k = 0; k < 8; ++k)
      crc = crc & 1 ? 0xEDB88320u ^ (crc >> 1) : crc >> 1;
  }
  return ~crc;
}

std::string
bigEndian (std::uint32_t v)
{
  return {static_cast<char> (v >> 24), static_cast<char> (v >> 16), static_cast<char> (v >> 8), static_cast<char> (v)};
}

void
writePalettePng (const std::string &path, const cv::Mat &indices, const std::vector<cv::Vec3b> &rgb)
{
  auto chunk = [] (const std::string &type, const std::string &data) {
    return bigEndian (static_cast<std::uint32_t> (data.size ())) + type + data + bigEndian (crc32Of (type + data));
  };
  std::string raw;
  for (int y = 0; y < indices.rows; ++y)
  {
    raw += '\0';  // filter: none
    raw.append (reinterpret_cast<const char *> (indices.ptr (y)), indices.cols);
  }
  std::string zlib = "\x78\x01";
  for (std::size_t at = 0; at < raw.size (); at += 65535)
  {
    const std::size_t n = std::min<std::size_t> (65535, raw.size () - at);
    zlib += static_cast<char> (at + n == raw.size ());
    zlib += {static_cast<char> (n & 0xFF), static_cast<char> (n >> 8), static_cast<char> (~n & 0xFF),
             static_cast<char> ((~n >> 8) & 0xFF)};
    zlib += raw.substr (at, n);
  }
  std::uint32_t a = 1, b = 0;
  for (const unsigned char c : raw)
  {
    a = (a + c) % 65521;
    b = (b + a) % 65521;
  }
  zlib += bigEndian (b << 16 | a);
  std::string palette;
  for (const cv::Vec3b &c : rgb)
    palette += {static_cast<char> (c[0]), static_cast<char> (c[1]), static_cast<char> (c[2])};
  const std::string ihdr = bigEndian (indices.cols) + bigEndian (indices.rows) + std::string ("\x08\x03\x00\x00\x00", 5);
  writeAll (path, std::string ("\x89PNG\r\n\x1a\n", 8) + chunk ("IHDR", ihdr) + chunk ("PLTE", palette) +
                    chunk ("IDAT", zlib) + chunk ("IEND", ""));
}

int
runCapturing (const std::string &command, const fs::path &dir, std::string *out, std::string *err)
{
  const std::string out_file = (dir / "stdout.txt").string (), err_file = (dir / "stderr.txt").string ();
  const int status = std::system ((command + " > " + out_file + " 2> " + err_file).c_str ());
  *out = readAll (out_file);
  *err = readAll (err_file);
  return WIFEXITED (status) ? WEXITSTATUS (status) : -1;
}

// An image sequence whose frames change size (640x480, then 550x830): each frame gives the
// people it gives as a still image (the later frames gave none when OpenCV's reader kept the
// first frame's size).
TEST (LandmarkApps, ImageSequenceFramesMayChangeSize)
{
  const fs::path dir = tempDir ("sequence_sizes");
  const cv::Mat still = cv::imread (std::string (AGEX_SOURCE_DIR) + "/data/images/five_people.jpg");
  ASSERT_FALSE (still.empty ());
  cv::Mat tall;
  cv::resize (still, tall, cv::Size (550, 830));
  const std::string first = (dir / "t0.png").string (), second = (dir / "t1.png").string ();
  ASSERT_TRUE (cv::imwrite (first, still));
  ASSERT_TRUE (cv::imwrite (second, tall));
  const std::string app = std::string (AGEX_LANDMARKS_EXECUTABLE) + " --opencv-detector";
  const std::string from_video = (dir / "video.json").string (), from_stills = (dir / "stills.json").string ();
  ASSERT_EQ (run (app + " --video " + (dir / "t%d.png").string () + " --json " + from_video), 0);
  ASSERT_EQ (run (app + " " + first + " " + second + " --json " + from_stills), 0);
  const nlohmann::json v = nlohmann::json::parse (readAll (from_video));
  const nlohmann::json s = nlohmann::json::parse (readAll (from_stills));
  ASSERT_EQ (v["frames"].size (), 2u);
  for (std::size_t n = 0; n < 2; ++n)
  {
    ASSERT_EQ (v["frames"][n]["people"].size (), s["frames"][n]["people"].size ()) << "frame " << n;
    for (std::size_t i = 0; i < v["frames"][n]["people"].size (); ++i)
      EXPECT_EQ (v["frames"][n]["people"][i]["box"], s["frames"][n]["people"][i]["box"]);
  }
  EXPECT_GT (s["frames"][1]["people"].size (), 0u) << "the resized frame has no people to compare";
  // A pattern with a second conversion is refused, not handed to a printf.
  const std::string log = (dir / "log.txt").string ();
  EXPECT_NE (std::system ((app + " --video " + (dir / "t%d%d.png").string () + " > " + log + " 2>&1").c_str ()), 0);
  EXPECT_NE (readAll (log).find ("an image sequence takes one %d or %0Nd"), std::string::npos) << readAll (log);
  // A still image given as the video is read as one (its size checked from its header): the
  // numbered ones after it with it, as OpenCV's image-sequence reader would.
  ASSERT_EQ (run (app + " --video " + first + " --json " + from_video), 0);
  EXPECT_EQ (nlohmann::json::parse (readAll (from_video))["frames"].size (), 2u);
  const std::string bomb = (dir / "bomb.png").string ();  // a TIFF that claims 32767 x 32767
  writeAll (bomb, std::string ("II*\0\x08\0\0\0\x02\0\0\x01\x04\0\x01\0\0\0\xff\x7f\0\0\x01\x01\x04\0\x01\0\0\0\xff\x7f\0\0"
                                "\0\0\0\0", 38));
  EXPECT_NE (std::system ((app + " --video " + bomb + " > " + log + " 2>&1").c_str ()), 0);
  EXPECT_NE (readAll (log).find ("claims a 32767x32767"), std::string::npos) << readAll (log);
  fs::remove_all (dir);
}

// Label maps (one person per image, excluded labels), instance masks in Penn-Fudan's layout
// (STEM_mask.png, palette PNGs), and the masks that cannot be used, each named with its reason.
TEST (LandmarkApps, AnnotateMaskFolders)
{
  const fs::path dir = tempDir ("masks");
  for (const char *sub : {"labels/images", "labels/masks", "peds/PNGImages", "peds/PedMasks"})
    fs::create_directories (dir / sub);
  const Figure f = drawFigure (cv::Size (300, 300), cv::Point2f (150, 150), 1.2f, 1.2f, 0.3f);
  cv::Mat labels = f.mask / 255 * 5;
  labels (cv::Rect (120, 146, 130, 14)).setTo (2);  // a bag across the waist, bulging to the right
  const cv::Mat photo = 40 + f.mask / 2;
  ASSERT_TRUE (cv::imwrite ((dir / "labels/images/person.png").string (), photo));
  ASSERT_TRUE (cv::imwrite ((dir / "labels/masks/person.png").string (), labels));
  ASSERT_TRUE (cv::imwrite ((dir / "labels/images/wrong.png").string (), photo));
  ASSERT_TRUE (cv::imwrite ((dir / "labels/masks/wrong.png").string (), labels (cv::Rect (0, 0, 200, 200))));
  ASSERT_TRUE (cv::imwrite ((dir / "labels/images/empty.png").string (), photo));
  ASSERT_TRUE (cv::imwrite ((dir / "labels/masks/empty.png").string (), cv::Mat::zeros (300, 300, CV_8UC1)));
  ASSERT_TRUE (cv::imwrite ((dir / "labels/images/junk.png").string (), photo));
  writeAll ((dir / "labels/masks/junk.png").string (), "not a PNG");
  ASSERT_TRUE (cv::imwrite ((dir / "labels/images/nomask.png").string (), photo));
  const std::string app = AGEX_ANNOTATE_EXECUTABLE, xml = (dir / "labels.xml").string ();
  std::string out, err;
  ASSERT_EQ (runCapturing (app + " masks --images " + (dir / "labels/images").string () + " --masks " +
                             (dir / "labels/masks").string () + " --labels-excluded 2,33,56 --out " + xml,
                           dir, &out, &err),
             0)
    << err;
  EXPECT_NE (out.find ("1 images, 1 people outlined, 0 ignore boxes, 4 images left out"), std::string::npos) << out;
  for (const char *expected : {"wrong.png: left out: mask of another size than its image", "empty.png: left out: empty mask",
                               "junk.png: left out: unreadable mask", "nomask.png: left out: no mask"})
    EXPECT_NE (err.find (expected), std::string::npos) << expected << "\n" << err;
  const agex::ImglabDataset d = agex::readImglabDataset (xml);
  ASSERT_EQ (d.images.size (), 1u);
  ASSERT_EQ (d.images[0].boxes.size (), 1u);
  const agex::ImglabBox &box = d.images[0].boxes[0];
  ASSERT_EQ (box.parts.size (), 180u);
  // The bag split the body; the outline still reaches the feet, and leaves the bag's bulge out.
  EXPECT_LT (cv::norm (box.parts.at ("072") - f.foot_left), 8.0) << box.parts.at ("072");
  EXPECT_LT (cv::norm (box.parts.at ("108") - f.foot_right), 8.0) << box.parts.at ("108");
  for (const auto &[name, p] : box.parts)
    EXPECT_LT (p.x, 215.f) << name << " " << p;

  // Penn-Fudan: PNGImages/X.png with PedMasks/X_mask.png, two people and one too small.
  cv::Mat peds = cv::Mat::zeros (300, 400, CV_8UC1);
  const Figure a = drawFigure (cv::Size (400, 300), cv::Point2f (100, 150), 1.2f, 0.6f, 0.3f);
  const Figure b = drawFigure (cv::Size (400, 300), cv::Point2f (290, 150), 1.2f, 1.1f, 0.3f);
  peds.setTo (1, a.mask);
  peds.setTo (2, b.mask);
  cv::rectangle (peds, cv::Rect (380, 10, 6, 20), 3, cv::FILLED);
  writePalettePng ((dir / "peds/PedMasks/FudanPed00001_mask.png").string (), peds,
                   {{0, 0, 0}, {128, 0, 0}, {0, 128, 0}, {128, 128, 0}, {0, 0, 0}});
  ASSERT_TRUE (cv::imwrite ((dir / "peds/PNGImages/FudanPed00001.png").string (), cv::Mat (40 + (a.mask | b.mask) / 2)));
  const std::string peds_xml = (dir / "peds.xml").string ();
  const std::string peds_command = app + " masks --images " + (dir / "peds/PNGImages").string () + " --masks " +
                                   (dir / "peds/PedMasks").string () + " --instances --out " + peds_xml;
  ASSERT_EQ (runCapturing (peds_command, dir, &out, &err), 0) << err;
  EXPECT_NE (err.find ("FudanPed00001.png: person 3: ignore box: shorter than 48 px"), std::string::npos) << err;
  const agex::ImglabDataset p = agex::readImglabDataset (peds_xml);
  ASSERT_EQ (p.images.size (), 1u);
  ASSERT_EQ (p.images[0].boxes.size (), 3u);
  EXPECT_EQ (p.images[0].boxes[0].parts.size (), 180u);
  EXPECT_LT (cv::norm (p.images[0].boxes[0].parts.at ("000") - a.head_top), 4.0);  // value 1 is the left one
  EXPECT_LT (cv::norm (p.images[0].boxes[1].parts.at ("000") - b.head_top), 4.0);
  EXPECT_TRUE (p.images[0].boxes[2].ignore);
  // Flags that contradict each other, and names that are not there.
  EXPECT_EQ (runCapturing (peds_command + " --labels-excluded 2", dir, &out, &err), 1);
  EXPECT_NE (err.find ("--labels-excluded applies to label maps"), std::string::npos) << err;
  EXPECT_EQ (runCapturing (peds_command + " --only FudanPed00002.png", dir, &out, &err), 1);
  EXPECT_EQ (runCapturing (peds_command + " --skip FudanPed00001.png", dir, &out, &err), 1);  // nothing left
  EXPECT_EQ (runCapturing (app + " masks --images " + (dir / "labels/images").string () + " --masks " +
                             (dir / "labels/masks").string () + " --labels-excluded 2,x --out " + xml,
                           dir, &out, &err),
             1);
  EXPECT_NE (err.find ("'x' is not a label"), std::string::npos) << err;
  fs::remove_all (dir);
}

// COCO RLE segmentations, compressed and as count lists, beside polygons; crowd annotations
// become ignore boxes and other categories are left out; the summary says why.
TEST (LandmarkApps, AnnotateCocoRleMasks)
{
  const fs::path dir = tempDir ("coco_rle");
  const cv::Size size (420, 300);
  std::vector<Figure> figures;
  cv::Mat all = cv::Mat::zeros (size, CV_8UC1);
  for (const float x : {80.f, 210.f, 340.f})
  {
    figures.push_back (drawFigure (size, cv::Point2f (x, 150), 1.1f, 0.9f, 0.3f));
    all |= figures.back ().mask;
  }
  ASSERT_TRUE (cv::imwrite ((dir / "people.png").string (), cv::Mat (40 + all / 2)));
  auto bbox = [] (const cv::Mat &mask) {
    const cv::Rect r = cv::boundingRect (mask);
    return nlohmann::json::array ({r.x, r.y, r.width, r.height});
  };
  const std::vector<std::uint32_t> counts0 = agex::cocoRleFromMask (figures[0].mask);
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours (figures[2].mask.clone (), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  std::vector<float> polygon;
  for (const cv::Point &q : contours[0])
    polygon.insert (polygon.end (), {static_cast<float> (q.x), static_cast<float> (q.y)});
  cv::Mat crowd = cv::Mat::zeros (size, CV_8UC1);
  crowd (cv::Rect (5, 5, 60, 40)).setTo (255);
  nlohmann::json coco = {
    {"images", {{{"id", 1}, {"file_name", "people.png"}, {"width", size.width}, {"height", size.height}}}},
    {"categories", {{{"id", 1}, {"name", "person"}}, {{"id", 18}, {"name", "dog"}}}},
    {"annotations",
     {{{"id", 10}, {"image_id", 1}, {"category_id", 1}, {"iscrowd", 0}, {"bbox", bbox (figures[0].mask)},
       {"segmentation", {{"size", {size.height, size.width}}, {"counts", agex::cocoRleString (counts0)}}}},
      {{"id", 11}, {"image_id", 1}, {"category_id", 1}, {"iscrowd", 0}, {"bbox", bbox (figures[1].mask)},
       {"segmentation", {{"size", {size.height, size.width}}, {"counts", agex::cocoRleFromMask (figures[1].mask)}}}},
      {{"id", 12}, {"image_id", 1}, {"category_id", 1}, {"iscrowd", 0}, {"bbox", bbox (figures[2].mask)},
       {"segmentation", {polygon}}},
      {{"id", 13}, {"image_id", 1}, {"category_id", 1}, {"iscrowd", 1}, {"bbox", bbox (crowd)},
       {"segmentation", {{"size", {size.height, size.width}}, {"counts", agex::cocoRleFromMask (crowd)}}}},
      {{"id", 14}, {"image_id", 1}, {"category_id", 18}, {"iscrowd", 0}, {"bbox", {1, 1, 5, 5}}, {"segmentation", {}}}}}};
  const std::string json = (dir / "coco.json").string (), xml = (dir / "coco.xml").string ();
  writeAll (json, coco.dump ());
  const std::string command = std::string (AGEX_ANNOTATE_EXECUTABLE) + " coco --json " + json + " --images " +
                              dir.string () + " --out " + xml;
  std::string out, err;
  ASSERT_EQ (runCapturing (command, dir, &out, &err), 0) << err;
  EXPECT_NE (out.find ("1 images, 3 people outlined, 1 ignore boxes (crowd annotation (iscrowd): 1)"), std::string::npos)
    << out;
  EXPECT_NE (err.find ("person 13: ignore box: crowd annotation (iscrowd)"), std::string::npos) << err;
  const agex::ImglabDataset d = agex::readImglabDataset (xml);
  ASSERT_EQ (d.images.size (), 1u);
  ASSERT_EQ (d.images[0].boxes.size (), 4u);
  for (int i = 0; i < 3; ++i)
  {
    // The same outline as the mask itself gives.
    const agex::ContourAnnotation direct = agex::annotateContour (figures[i].mask, agex::ContourAnchors ());
    ASSERT_TRUE (direct.ok);
    EXPECT_LT (cv::norm (d.images[0].boxes[i].parts.at ("000") - direct.landmarks[0]), 1.5) << i;
    EXPECT_LT (cv::norm (d.images[0].boxes[i].parts.at ("090") - direct.landmarks[90]), 1.5) << i;
  }
  EXPECT_TRUE (d.images[0].boxes[3].ignore);
  // An RLE of another size than the image, and a damaged RLE string, name the annotation.
  coco["annotations"][0]["segmentation"]["size"] = {200, size.width};
  writeAll (json, coco.dump ());
  EXPECT_EQ (runCapturing (command, dir, &out, &err), 1);
  EXPECT_NE (err.find ("people.png: person 10: the RLE mask is 420x200"), std::string::npos) << err;
  coco["annotations"][0]["segmentation"] = {{"size", {size.height, size.width}}, {"counts", "25 4"}};
  writeAll (json, coco.dump ());
  EXPECT_EQ (runCapturing (command, dir, &out, &err), 1);
  EXPECT_NE (err.find ("person 10: character ' ' at 2"), std::string::npos) << err;
  fs::remove_all (dir);
}

// The evaluation reports detection AP, false detections per image and the contour distance
// per box height; a deeply nested dataset is refused by name (it crashed the app before).
// --detector opencv-hog (issue 35) selects OpenCV's pretrained detector: the same people and
// description as --opencv-detector, not a file of that name; with a trained detector's file it
// would be an error, and the bundled detector's description differs.
TEST (LandmarkApps, DetectorFlagSelectsOpenCvHog)
{
  const fs::path dir = tempDir ("opencv_hog");
  const std::string image = std::string (AGEX_SOURCE_DIR) + "/data/images/five_people.jpg";
  const std::string app = AGEX_LANDMARKS_EXECUTABLE;
  std::string out, err;
  std::map<std::string, nlohmann::json> docs;
  for (const std::string flag : {"--detector opencv-hog", "--opencv-detector", ""})
  {
    const std::string json = (dir / ("people" + std::to_string (docs.size ()) + ".json")).string ();
    ASSERT_EQ (runCapturing (app + " " + image + " " + flag + " --json " + json, dir, &out, &err), 0) << flag << ": " << err;
    docs[flag] = nlohmann::json::parse (readAll (json));
  }
  const std::string hog = docs["--detector opencv-hog"]["detector"];
  EXPECT_NE (hog.find ("OpenCV"), std::string::npos) << hog;
  EXPECT_EQ (docs["--detector opencv-hog"]["detector"], docs["--opencv-detector"]["detector"]);
  EXPECT_NE (docs[""]["detector"], docs["--opencv-detector"]["detector"]);
  const auto boxes = [] (const nlohmann::json &doc) {
    std::vector<nlohmann::json> out;
    for (const auto &person : doc["frames"][0]["people"])
      out.push_back (person["box"]);
    return out;
  };
  EXPECT_FALSE (boxes (docs["--opencv-detector"]).empty ());
  EXPECT_EQ (boxes (docs["--detector opencv-hog"]), boxes (docs["--opencv-detector"]));
  // The evaluation app takes the same flag.
  const std::string eval = AGEX_LANDMARKS_EVAL_EXECUTABLE;
  agex::ImglabDataset dataset;
  const Figure f = drawFigure (cv::Size (260, 260), cv::Point2f (130, 130), 1.2f, 0.4f, 0.3f);
  ASSERT_TRUE (cv::imwrite ((dir / "figure.png").string (), cv::Mat (40 + f.mask / 2)));
  const agex::ContourAnnotation a = agex::annotateContour (f.mask, agex::ContourAnchors ());
  agex::ImglabImage entry;
  entry.file = "figure.png";
  agex::ImglabBox box;
  box.rect = a.box;
  for (int k = 0; k < agex::kContourLandmarkCount; ++k)
    box.parts[agex::contourLandmarkName (k)] = a.landmarks[k];
  entry.boxes.push_back (box);
  dataset.images.push_back (entry);
  agex::writeImglabDataset ((dir / "figure.xml").string (), dataset);
  const std::string json = (dir / "eval.json").string ();
  ASSERT_EQ (runCapturing (eval + " --dataset " + (dir / "figure.xml").string () + " --model " + AGEX_SOURCE_DIR +
                             "/data/models/agex_contour_landmarks.dat --detector opencv-hog --json " + json,
                           dir, &out, &err),
             0)
    << err;
  EXPECT_EQ (nlohmann::json::parse (readAll (json))["detector"], docs["--opencv-detector"]["detector"]);
  fs::remove_all (dir);
}

TEST (LandmarkApps, EvalReportsDetectionAndRefusesDeepFiles)
{
  const fs::path dir = tempDir ("eval");
  agex::ImglabDataset dataset;
  std::vector<double> box_heights;
  for (int i = 0; i < 3; ++i)
  {
    const Figure f = drawFigure (cv::Size (260, 260), cv::Point2f (120.f + 10 * i, 130), 1.2f, 0.4f + 0.3f * i, 0.3f);
    const std::string image = "figure" + std::to_string (i) + ".png";
    ASSERT_TRUE (cv::imwrite ((dir / image).string (), cv::Mat (40 + f.mask / 2)));
    const agex::ContourAnnotation a = agex::annotateContour (f.mask, agex::ContourAnchors ());
    ASSERT_TRUE (a.ok);
    agex::ImglabImage entry;
    entry.file = image;
    agex::ImglabBox box;
    box.rect = a.box;
    box_heights.push_back (a.box.height);
    for (int k = 0; k < agex::kContourLandmarkCount; ++k)
      box.parts[agex::contourLandmarkName (k)] = a.landmarks[k];
    entry.boxes.push_back (box);
    dataset.images.push_back (entry);
  }
  const std::string xml = (dir / "figures.xml").string (), json = (dir / "eval.json").string ();
  agex::writeImglabDataset (xml, dataset);
  const std::string app = AGEX_LANDMARKS_EVAL_EXECUTABLE;
  std::string out, err;
  ASSERT_EQ (runCapturing (app + " --dataset " + xml + " --model " + AGEX_SOURCE_DIR +
                             "/data/models/agex_contour_landmarks.dat --opencv-detector --json " + json,
                           dir, &out, &err),
             0)
    << err;
  const nlohmann::json doc = nlohmann::json::parse (readAll (json));
  EXPECT_EQ (doc["people"], 3);
  EXPECT_EQ (doc["detection_people"], 3);
  for (const char *key : {"detection_ap", "detection_recall", "false_detections_per_image", "mean_contour_distance_px",
                          "mean_contour_distance_box_height", "mean_error_box_height"})
    EXPECT_TRUE (doc[key].is_number ()) << key << ": " << doc[key];
  // The mean of distance / box height lies between the mean distance over the largest and over
  // the smallest box.
  const double px = doc["mean_contour_distance_px"], per_box = doc["mean_contour_distance_box_height"];
  EXPECT_GT (px, 0.0);
  EXPECT_GE (per_box, px / *std::max_element (box_heights.begin (), box_heights.end ()) - 1e-9);
  EXPECT_LE (per_box, px / *std::min_element (box_heights.begin (), box_heights.end ()) + 1e-9);
  ASSERT_EQ (runCapturing (app + " --dataset " + xml + " --model " + AGEX_SOURCE_DIR +
                             "/data/models/agex_contour_landmarks.dat --no-detector --json " + json,
                           dir, &out, &err),
             0);
  EXPECT_TRUE (nlohmann::json::parse (readAll (json))["detection_ap"].is_null ());

  std::string deep = "<dataset>\n<images>\n";
  for (int i = 0; i < 50000; ++i)
    deep += "<image file='a.png'>";
  writeAll ((dir / "deep.xml").string (), deep);
  EXPECT_EQ (runCapturing (app + " --dataset " + (dir / "deep.xml").string () + " --model " + AGEX_SOURCE_DIR +
                             "/data/models/agex_contour_landmarks.dat --no-detector",
                           dir, &out, &err),
             1);  // a stack overflow was a signal, not exit code 1
  EXPECT_NE (err.find ((dir / "deep.xml").string () + ": line 3: elements nested more than 64 deep"), std::string::npos)
    << err;
  fs::remove_all (dir);
}
}  // namespace
