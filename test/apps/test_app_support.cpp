// The apps' shared safety code: which outputs may be replaced (checkOutputPath, the PNG
// mark), the locked JSON-lines results file (resume, torn-line repair, a second writer
// refused) and the canonical frame names a resumed run finds its frames by.

#include "test_support.h"

#include <agex/apps/detect_runs.h>
#include <agex/apps/frame_jobs.h>
#include <agex/apps/output.h>
#include <agex/apps/output_guard.h>
#include <agex/apps/results_file.h>
#include <agex/io/dataset.h>

#include <opencv2/imgcodecs.hpp>

#include <pcl/io/pcd_io.h>

#include <nlohmann/json.hpp>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <set>
#include <thread>

namespace
{
using agex::apps::OutputKind;
using agex_test::readAll;
using agex_test::TempDir;
using agex_test::writeAll;
namespace fs = std::filesystem;

/** Runs f, expecting a std::runtime_error whose message contains every needle. */
template <typename F>
void
expectRefusal (F &&f, const std::vector<std::string> &needles)
{
  try
  {
    f ();
    ADD_FAILURE () << "not refused";
  }
  catch (const std::runtime_error &e)
  {
    for (const auto &needle : needles)
      EXPECT_NE (std::string (e.what ()).find (needle), std::string::npos) << "'" << needle << "' not in: " << e.what ();
  }
}

/** A small agex dataset of two 4x3 frames. */
void
writeDataset (const std::string &directory)
{
  agex::DatasetInfo info;
  info.name = "test";
  info.sensor = "test";
  info.width = 4;
  info.height = 3;
  info.intrinsics = {200.0, 200.0, 1.5, 1.0};
  agex::DatasetWriter writer (directory, info);
  for (const char *id : {"f0", "f1"})
    writer.addFrame (id, "s", agex_test::Cloud (4, 3, pcl::PointXYZ (0.f, 0.f, 1.f)), {});
  writer.commit ();
}

std::string
pngBytes ()
{
  std::vector<unsigned char> bytes;
  EXPECT_TRUE (cv::imencode (".png", cv::Mat (5, 7, CV_8UC3, cv::Scalar (1, 2, 3)), bytes));
  return std::string (bytes.begin (), bytes.end ());
}

TEST (OutputGuard, DatasetsReplacedOnlyWhenTheyAreEarlierDatasets)
{
  TempDir tmp;
  const agex::InputFiles none;
  const std::string ds = tmp.file ("ds");
  EXPECT_NO_THROW (agex::apps::checkOutputPath (ds, OutputKind::Dataset, none)) << "nothing there yet";
  writeDataset (ds);
  expectRefusal ([&] { agex::apps::checkOutputPath (ds, OutputKind::Dataset, none); },
                 {ds, "already exists; pass --force"});
  EXPECT_NO_THROW (agex::apps::checkOutputPath (ds, OutputKind::Dataset, none, true));

  // Never something else, with or without --force.
  const std::string file = tmp.file ("thesis.txt");
  writeAll (file, "chapter 1");
  for (bool force : {false, true})
    expectRefusal ([&] { agex::apps::checkOutputPath (file, OutputKind::Dataset, none, force); },
                   {file, "is a regular file, not an agex dataset", "--force replaces only an earlier agex dataset"});
  const std::string dir = tmp.file ("notes");
  fs::create_directories (dir);
  expectRefusal ([&] { agex::apps::checkOutputPath (dir, OutputKind::Dataset, none, true); },
                 {dir, "without an agex dataset.json"});
  writeAll (ds + "/README", "mine");
  expectRefusal ([&] { agex::apps::checkOutputPath (ds, OutputKind::Dataset, none, true); }, {"holds README"});
  fs::remove (ds + "/README");

  // Never an input or a directory above one: the dataset given as the input itself, or a
  // directory holding the input frames.
  agex::InputFiles inputs ({ds + "/frames/f0.pcd"});
  expectRefusal ([&] { agex::apps::checkOutputPath (ds, OutputKind::Dataset, inputs, true); },
                 {ds, "holds an input file"});
  expectRefusal ([&] { agex::apps::checkOutputPath (tmp.path ().string (), OutputKind::Dataset, inputs, true); },
                 {"holds an input file"});
  EXPECT_EQ (readAll (file), "chapter 1");
}

TEST (OutputGuard, FilesReplacedOnlyWhenTheyAreEarlierOutputsOfTheirKind)
{
  TempDir tmp;
  agex::InputFiles inputs;
  const std::string doc = tmp.file ("frame.json"), lines = tmp.file ("frames.jsonl"), text = tmp.file ("notes.txt");
  agex::apps::writeJson (doc, {{"frame", "d/f.png"}, {"detections", nlohmann::json::array ()}});
  writeAll (lines, "{\"frame\":\"d/a.png\",\"detections\":[]}\n{\"frame\":\"d/b.png\",\"detections\":[]}\n");
  writeAll (text, "my notes\n");
  EXPECT_NO_THROW (agex::apps::checkOutputPath (doc, OutputKind::JsonDocument, inputs));
  EXPECT_NO_THROW (agex::apps::checkOutputPath (tmp.file ("new.json"), OutputKind::JsonDocument, inputs));
  expectRefusal ([&] { agex::apps::checkOutputPath (lines, OutputKind::JsonDocument, inputs); },
                 {lines, "is a JSON-lines results file"});
  writeAll (lines, "{\"frame\":\"d/a.png\",\"detections\":[]}\n");  // one line: still JSON lines
  expectRefusal ([&] { agex::apps::checkOutputPath (lines, OutputKind::JsonDocument, inputs); },
                 {"is a JSON-lines results file"});
  expectRefusal ([&] { agex::apps::checkOutputPath (text, OutputKind::JsonDocument, inputs); },
                 {text, "not a JSON document of a frame"});
  writeAll (tmp.file ("report.json"), "{\n  \"frames\": 3\n}\n");  // JSON, but not a frame's
  expectRefusal ([&] { agex::apps::checkOutputPath (tmp.file ("report.json"), OutputKind::JsonDocument, inputs); },
                 {"not a JSON document of a frame"});
  expectRefusal ([&] { agex::apps::checkOutputPath (tmp.path ().string (), OutputKind::JsonDocument, inputs); },
                 {"is a directory"});
  writeAll (tmp.file ("empty"), "");
  EXPECT_NO_THROW (agex::apps::checkOutputPath (tmp.file ("empty"), OutputKind::Png, inputs)) << "nothing to lose";

  // PNGs: those agex wrote carry its mark; any other PNG (a photo, a depth frame) is refused.
  const std::string ours = tmp.file ("overlay.png"), theirs = tmp.file ("photo.png");
  agex::apps::writePng (ours, cv::Mat (5, 7, CV_8UC3, cv::Scalar (1, 2, 3)));
  writeAll (theirs, pngBytes ());
  EXPECT_TRUE (agex::apps::isAgexPng (readAll (ours)));
  EXPECT_FALSE (agex::apps::isAgexPng (readAll (theirs)));
  EXPECT_NO_THROW (agex::apps::checkOutputPath (ours, OutputKind::Png, inputs));
  expectRefusal ([&] { agex::apps::checkOutputPath (theirs, OutputKind::Png, inputs); },
                 {theirs, "not a PNG written by agex"});
  expectRefusal ([&] { agex::apps::checkOutputPath (text, OutputKind::Png, inputs); }, {"not a PNG written by agex"});
  // The mark changes nothing of the image.
  const cv::Mat a = cv::imread (ours, cv::IMREAD_UNCHANGED), b = cv::imread (theirs, cv::IMREAD_UNCHANGED);
  ASSERT_FALSE (a.empty ());
  EXPECT_EQ (cv::norm (a, b, cv::NORM_INF), 0.0);
  EXPECT_EQ (agex::apps::markAgexPng ("not a png"), "not a png");

  // Inputs and everything inside an input dataset stay out of reach.
  const std::string ds = tmp.file ("ds");
  writeDataset (ds);
  inputs.addTree (ds);
  inputs.add (text);
  expectRefusal ([&] { agex::apps::checkOutputPath (text, OutputKind::JsonDocument, inputs); },
                 {text, "would overwrite an input"});
  expectRefusal ([&] { agex::apps::checkOutputPath (ds + "/frames/f1.pcd", OutputKind::Png, inputs); },
                 {"f1.pcd", "would land inside the input dataset"});
  expectRefusal ([&] { agex::apps::checkOutputPath (ds + "/new.json", OutputKind::JsonDocument, inputs); },
                 {"new.json", "would land inside the input dataset"});
  EXPECT_EQ (readAll (text), "my notes\n");
}

TEST (OutputGuard, ReportsModelsAndDatasetsRecognisedByTheirContent)
{
  TempDir tmp;
  const agex::InputFiles inputs;
  const std::string notes = tmp.file ("notes.txt"), config = tmp.file ("config.json");
  writeAll (notes, "my notes\n");
  writeAll (config, "{\"threads\": 4}\n");  // a JSON object of someone else's
  const auto report = agex::apps::jsonReportWith ({"frames", "detector"});
  writeAll (tmp.file ("r.json"), "{\"frames\": [], \"detector\": \"fhog\", \"model\": \"m\"}");
  EXPECT_NO_THROW (agex::apps::checkOutputPath (tmp.file ("r.json"), "report", report, inputs));
  expectRefusal ([&] { agex::apps::checkOutputPath (config, "report", report, inputs); },
                 {config, "without \"frames\"", "(report)"});
  expectRefusal ([&] { agex::apps::checkOutputPath (notes, "report", report, inputs); }, {notes, "not a JSON object"});

  const auto lines = agex::apps::jsonLinesWith ({"source", "people"});
  writeAll (tmp.file ("l.jsonl"), "{\"source\": \"a\", \"people\": []}\n{\"source\": \"b\", \"people\": []}\n");
  writeAll (tmp.file ("mixed.jsonl"), "{\"source\": \"a\", \"people\": []}\nmy notes\n");
  EXPECT_NO_THROW (agex::apps::checkOutputPath (tmp.file ("l.jsonl"), "lines", lines, inputs));
  expectRefusal ([&] { agex::apps::checkOutputPath (tmp.file ("mixed.jsonl"), "lines", lines, inputs); }, {"line 2"});
  expectRefusal ([&] { agex::apps::checkOutputPath (config, "lines", lines, inputs); }, {"line 1"});

  writeAll (tmp.file ("model.yml"), "%YAML:1.0\n---\nformat: agex-model\nformat_version: 2\n");
  writeAll (tmp.file ("other.yml"), "%YAML:1.0\n---\nname: my settings\n");
  EXPECT_NO_THROW (agex::apps::checkOutputPath (tmp.file ("model.yml"), OutputKind::Model, inputs));
  expectRefusal ([&] { agex::apps::checkOutputPath (tmp.file ("other.yml"), OutputKind::Model, inputs); },
                 {"other.yml", "is not an agex model"});

  writeAll (tmp.file ("ours.xml"), "<?xml version='1.0'?>\n<dataset>\n<name>x</name>\n<comment>agex_annotate masks from m</comment>\n");
  writeAll (tmp.file ("theirs.xml"), "<?xml version='1.0'?>\n<dataset>\n<name>hand-made</name>\n");
  EXPECT_NO_THROW (agex::apps::checkOutputPath (tmp.file ("ours.xml"), OutputKind::ImglabXml, inputs));
  expectRefusal ([&] { agex::apps::checkOutputPath (tmp.file ("theirs.xml"), OutputKind::ImglabXml, inputs); },
                 {"theirs.xml", "not an imglab dataset written by agex_annotate"});
  EXPECT_EQ (readAll (notes), "my notes\n");
}

TEST (OutputGuard, PngsInAFolderAreCheckedBeforeAnyIsWritten)
{
  TempDir tmp;
  const std::string dir = tmp.file ("plots");
  std::filesystem::create_directories (dir);
  agex::apps::writePng (dir + "/a.png", cv::Mat (3, 3, CV_8UC3, cv::Scalar (1, 2, 3)));
  writeAll (dir + "/b.png", pngBytes ());  // the user's own picture
  const agex::InputFiles inputs;
  EXPECT_NO_THROW (agex::apps::checkPngsInFolder ({dir + "/a.png", dir + "/new.png"}, inputs));
  expectRefusal ([&] { agex::apps::checkPngsInFolder ({dir + "/a.png", dir + "/b.png"}, inputs); },
                 {"b.png", "not a PNG written by agex"});
  writeAll (tmp.file ("file"), "x");
  expectRefusal ([&] { agex::apps::checkPngsInFolder ({tmp.file ("file") + "/a.png"}, inputs); }, {"is not a folder"});
  EXPECT_EQ (readAll (dir + "/b.png"), pngBytes ());
}

TEST (OutputGuard, AClaimedSetIsWrittenByOneRunAtATime)
{
  TempDir tmp;
  const std::string json = tmp.file ("j.json"), png = tmp.file ("sub/o.png");
  std::filesystem::create_directories (tmp.file ("sub"));
  std::atomic<bool> second_claimed{false};
  std::thread second;
  {
    const agex::apps::OutputSetClaim claim ({json, png, ""});
    second = std::thread ([&] {
      const agex::apps::OutputSetClaim other ({png, json});  // the same folders, named in another order
      second_claimed = true;
    });
    std::this_thread::sleep_for (std::chrono::milliseconds (200));
    EXPECT_FALSE (second_claimed) << "a second claim on the same folders did not wait";
  }
  second.join ();
  EXPECT_TRUE (second_claimed);
  // Folders that do not exist (yet) or cannot be opened are no reason to fail.
  EXPECT_NO_THROW (agex::apps::OutputSetClaim ({tmp.file ("missing/x.json")}));
}

TEST (ResultsFile, ResumesRepairsATornLineInPlaceAndRefusesForeignFiles)
{
  TempDir tmp;
  const std::string path = tmp.file ("r.jsonl");
  {
    agex::apps::ResultsFile results (path, "test");
    EXPECT_EQ (results.doneCount (), 0u);
    results.append ("{\"frame\":\"d/a\"}");
    results.append ("{\"frame\":\"d/b\"}");
  }
  struct stat before;
  ASSERT_EQ (::stat (path.c_str (), &before), 0);
  // A torn last line (killed inside a write) is cut off, in place: the same file, so that a
  // lock taken on it stays meaningful.
  writeAll (path, readAll (path) + "{\"frame\":\"d/c");
  {
    agex::apps::ResultsFile results (path, "test");
    EXPECT_EQ (results.doneCount (), 2u);
    EXPECT_TRUE (results.contains ("d/a"));
    EXPECT_FALSE (results.contains ("d/c"));
    results.append ("{\"frame\":\"d/c\"}");
  }
  struct stat after;
  ASSERT_EQ (::stat (path.c_str (), &after), 0);
  EXPECT_EQ (before.st_ino, after.st_ino) << "repaired in place, not replaced";
  EXPECT_EQ (readAll (path), "{\"frame\":\"d/a\"}\n{\"frame\":\"d/b\"}\n{\"frame\":\"d/c\"}\n");
  // A complete last line without its newline gets one before the next line.
  writeAll (path, "{\"frame\":\"d/a\"}");
  {
    agex::apps::ResultsFile results (path, "test");
    results.append ("{\"frame\":\"d/b\"}");
  }
  EXPECT_EQ (readAll (path), "{\"frame\":\"d/a\"}\n{\"frame\":\"d/b\"}\n");

  // Someone else's file is left as it is, whatever line is not a result.
  // A one-line file that is not JSON but starts with "{" (no newline) is no torn result either.
  for (const std::string foreign : {"my notes\n", "{\"frame\":\"d/a\"}\nnot json\n{\"frame\":\"d/b\"}\n",
                                     "{\"frame\":\"d/a\"}\n{\"x\":1}", "{\"frame\":3}\n", "{a: 1}", "{\"name\": \"my"})
  {
    writeAll (path, foreign);
    expectRefusal ([&] { agex::apps::ResultsFile results (path, "test"); }, {path, "is not a frame result of test"});
    EXPECT_EQ (readAll (path), foreign);
  }
  // A first line torn as agex writes them (killed inside the run's first write) is cut off.
  for (const char *cut : {"{\"detections\":[{\"cla", "{\"ba", "{"})
  {
    const std::string torn = cut;
    writeAll (path, torn);
    {
      agex::apps::ResultsFile results (path, "test");
      EXPECT_EQ (results.doneCount (), 0u);
      results.append ("{\"frame\":\"d/a\"}");
    }
    EXPECT_EQ (readAll (path), "{\"frame\":\"d/a\"}\n") << torn;
  }
  expectRefusal ([&] { agex::apps::ResultsFile results (tmp.path ().string (), "test"); }, {"is a directory"});
  const std::string fifo = tmp.file ("fifo.jsonl");
  ASSERT_EQ (::mkfifo (fifo.c_str (), 0600), 0);
  expectRefusal ([&] { agex::apps::ResultsFile results (fifo, "test"); }, {"FIFO"});
}

TEST (ResultsFile, ASecondWriterIsRefusedWhileTheFirstHoldsTheFile)
{
  TempDir tmp;
  const std::string path = tmp.file ("r.jsonl");
  agex::apps::ResultsFile first (path, "agex_detect");
  first.append ("{\"frame\":\"d/a\"}");
  // In this process (flock locks belong to the open file, not the process) and in another.
  expectRefusal ([&] { agex::apps::ResultsFile second (path, "agex_detect"); },
                 {path, "another agex_detect run is writing to this file"});
  const pid_t child = ::fork ();
  ASSERT_GE (child, 0);
  if (child == 0)
  {
    try
    {
      agex::apps::ResultsFile second (path, "agex_detect");
      ::_exit (0);
    }
    catch (const std::runtime_error &e)
    {
      ::_exit (std::string (e.what ()).find ("is locked") != std::string::npos ? 3 : 1);
    }
  }
  int status = 0;
  ASSERT_EQ (::waitpid (child, &status, 0), child);
  ASSERT_TRUE (WIFEXITED (status));
  EXPECT_EQ (WEXITSTATUS (status), 3) << "the other process must be refused because of the lock";
  EXPECT_EQ (readAll (path), "{\"frame\":\"d/a\"}\n");
}

TEST (ResultsFile, AFileThisRunCreatedAndNeverWroteIsRemoved)
{
  TempDir tmp;
  const std::string path = tmp.file ("r.jsonl");
  {
    agex::apps::ResultsFile results (path, "test");
    EXPECT_TRUE (fs::exists (path)) << "created at once, so that it can be locked";
  }
  EXPECT_FALSE (fs::exists (path)) << "a run that failed before its first frame leaves nothing";
  writeAll (path, "");
  {
    agex::apps::ResultsFile results (path, "test");
  }
  EXPECT_TRUE (fs::exists (path)) << "a file that was there before stays";
}

TEST (FrameJobs, NamesAreCanonicalHoweverTheInputIsSpelled)
{
  TempDir tmp;
  const std::string dir = tmp.file ("batch");
  fs::create_directories (dir);
  for (const char *name : {"b.u16", "a.u16", "notes.txt"})
    writeAll (dir + "/" + name, "x");
  const std::string ds = tmp.file ("ds");
  writeDataset (ds);
  agex::InputFiles read;
  const auto jobs = agex::apps::collectFrameJobs ({dir + "/", dir + "/./a.u16", ds}, read, "test");
  std::vector<std::string> names;
  for (const auto &j : jobs)
    names.push_back (j.name);
  EXPECT_EQ (names, (std::vector<std::string>{"batch/a.u16", "batch/b.u16", "ds/f0", "ds/f1"}))
      << "directories sorted, a frame given twice processed once, dataset frames by id";

  // The same frames by other spellings: relative to another directory, a frame of the
  // dataset given on its own.
  const fs::path cwd = fs::current_path ();
  fs::current_path (tmp.path ());
  agex::InputFiles read2;
  const auto again = agex::apps::collectFrameJobs ({"batch/b.u16", "./ds/frames/f1.pcd"}, read2, "test");
  fs::current_path (cwd);
  ASSERT_EQ (again.size (), 2u);
  EXPECT_EQ (again[0].name, "batch/b.u16");
  EXPECT_EQ (again[1].name, "ds/f1");
  // A frame given on its own protects its whole dataset.
  expectRefusal ([&] { read2.checkOutput (ds + "/labels.csv"); }, {"inside the input dataset"});
  // Every file read is an input; the dataset's own files too.
  expectRefusal ([&] { read.checkOutput (ds + "/labels.csv"); }, {"would overwrite an input"});

  // Two different files of one name would share their results' key: refused.
  const std::string other = tmp.file ("elsewhere/batch");
  fs::create_directories (other);
  writeAll (other + "/a.u16", "y");
  agex::InputFiles read3;
  expectRefusal ([&] { agex::apps::collectFrameJobs ({dir, other}, read3, "test"); },
                 {"has the same name 'batch/a.u16'", "separate runs"});
  expectRefusal ([&] { agex::apps::collectFrameJobs ({tmp.file ("nope")}, read3, "test"); }, {"no such file"});
}

TEST (FrameJobs, BatchSkipsDoneFramesAndKeepsWhatWasDoneAfterAFailure)
{
  TempDir tmp;
  std::vector<agex::apps::FrameJob> jobs;
  for (int i = 0; i < 20; ++i)
    jobs.push_back ({"d/" + std::to_string (i), ""});
  const std::string path = tmp.file ("r.jsonl");
  writeAll (path, "{\"frame\":\"d/0\"}\n{\"frame\":\"d/1\"}\n");
  std::atomic<int> calls{0};
  {
    agex::apps::ResultsFile results (path, "test");
    agex::apps::runFrameBatch (jobs, &results, 4, [&] (const agex::apps::FrameJob &job) {
      ++calls;
      return nlohmann::json{{"frame", job.name}};
    });
  }
  EXPECT_EQ (calls.load (), 18) << "the two frames already there are skipped";
  std::set<std::string> frames;
  std::istringstream in (readAll (path));
  int lines = 0;
  for (std::string line; std::getline (in, line); ++lines)
    frames.insert (nlohmann::json::parse (line).at ("frame").get<std::string> ());
  EXPECT_EQ (lines, 20);
  EXPECT_EQ (frames.size (), 20u);

  // A failing frame stops the run; the frames done are kept and named in the message.
  const std::string path2 = tmp.file ("r2.jsonl");
  agex::apps::ResultsFile results (path2, "test");
  expectRefusal (
      [&] {
        agex::apps::runFrameBatch (jobs, &results, 1, [&] (const agex::apps::FrameJob &job) {
          if (job.name == "d/5")
            throw std::runtime_error ("d/5: damaged");
          return nlohmann::json{{"frame", job.name}};
        });
      },
      {"d/5: damaged", "the frames done are kept in " + path2});
  const std::string written = readAll (path2);
  EXPECT_EQ (std::count (written.begin (), written.end (), '\n'), 5);
}

// The detector flags' window model: a fused model brings the one it names with its weight,
// --window-model replaces it (weight 0.3 unless given), --window-weight 0 turns it off, and a
// weight without any window model is refused. The forest stays the forest in the reports.
TEST (DetectorFlags, AFusedModelBringsItsWindowModelUnlessTurnedOff)
{
  namespace fs = std::filesystem;
  const std::string models = AGEX_SOURCE_DIR "/data/models/";
  const auto same = [] (const std::string &a, const std::string &b) {
    return fs::weakly_canonical (a) == fs::weakly_canonical (b);
  };
  agex::apps::DetectorChoice choice;
  choice.model = models + "agex_bonn.yml";
  agex::apps::LoadedDetector own = agex::apps::loadDetector (choice, agex::DetectorKind::Fused);
  ASSERT_TRUE (own.window_model);
  EXPECT_TRUE (same (own.window_file, models + "agex_bonn_sw.yml")) << own.window_file;
  EXPECT_FLOAT_EQ (own.window_weight, own.model->settings ().window_weight);
  EXPECT_TRUE (same (own.forest_file, models + "agex_bonn_forest.agexforest")) << own.forest_file;
  EXPECT_EQ (own.files.size (), 3u);
  agex::BodyPartDetector<pcl::PointXYZ> detector;
  own.configure (detector);
  EXPECT_EQ (detector.getWindowModel (), own.window_model);
  EXPECT_FLOAT_EQ (detector.getWindowWeight (), own.window_weight);

  choice.window_weight = 0.f;
  const agex::apps::LoadedDetector off = agex::apps::loadDetector (choice, agex::DetectorKind::Fused);
  EXPECT_FALSE (off.window_model);
  EXPECT_TRUE (off.window_file.empty ());
  EXPECT_EQ (off.files.size (), 2u);

  choice.window_weight = -1.f;  // not given
  choice.window_model = models + "agex_bonn_sw.yml";
  const agex::apps::LoadedDetector given = agex::apps::loadDetector (choice, agex::DetectorKind::Fused);
  ASSERT_TRUE (given.window_model);
  EXPECT_EQ (given.window_file, choice.window_model);
  EXPECT_FLOAT_EQ (given.window_weight, agex::BodyPartDetector<pcl::PointXYZ>::kDefaultWindowWeight);

  choice.window_model = models + "agex_bonn_agex.yml";
  EXPECT_THROW (agex::apps::loadDetector (choice, agex::DetectorKind::Fused), std::invalid_argument);
  agex::apps::DetectorChoice agex_only;
  agex_only.model = models + "agex_bonn_agex.yml";
  agex_only.window_weight = 0.5f;
  EXPECT_THROW (agex::apps::loadDetector (agex_only), std::runtime_error);
  agex_only.window_weight = -1.f;
  EXPECT_FALSE (agex::apps::loadDetector (agex_only).window_model);
}

// agex_detect's detectors: one per thread at work, kept from frame to frame. A frame through a
// detector that has seen others gives what a new detector gives, also when a PCD (no
// intrinsics: focal lengths estimated) follows a depth image (intrinsics given).
TEST (DetectorPool, AKeptDetectorGivesWhatANewOneGives)
{
  const std::string png = agex_test::sharedData ("bonn/depth/3/021.png");
  const std::string other = agex_test::sharedData ("bonn/depth/7/001.png");
  AGEX_REQUIRE_BONN (png);
  AGEX_REQUIRE_BONN (other);
  TempDir dir;
  const std::string pcd = dir.file ("021.pcd");
  ASSERT_EQ (pcl::io::savePCDFileBinary (pcd, *agex::loadFrame (png).cloud), 0);

  agex::apps::DetectorChoice choice;
  choice.model = AGEX_SOURCE_DIR "/data/models/agex_bonn.yml";
  const agex::apps::LoadedDetector loaded = agex::apps::loadDetector (choice, agex::DetectorKind::Fused);
  agex::apps::DetectFlags flags;  // the depth images seen through another lens than the PCD's
  flags.frame_options.intrinsics.fx = flags.frame_options.intrinsics.fy = 400.0;
  flags.frame_options.intrinsics_width = flags.frame_options.intrinsics_height = 0;
  auto detections = [&] (agex::apps::DetectorPool &pool, const std::string &path) {
    return agex::apps::detectFrame ({path, path}, pool, flags)["detections"];
  };
  agex::apps::DetectorPool kept (loaded);
  const nlohmann::json first = detections (kept, other);
  const nlohmann::json from_png = detections (kept, png);
  const nlohmann::json from_pcd = detections (kept, pcd);
  EXPECT_EQ (kept.size (), 1u);
  for (const auto &[path, seen] : {std::pair<std::string, nlohmann::json>{png, from_png}, {pcd, from_pcd}, {other, first}})
  {
    agex::apps::DetectorPool fresh (loaded);
    EXPECT_EQ (detections (fresh, path), seen) << path;
  }
  EXPECT_FALSE (from_png.empty ());
  EXPECT_FALSE (from_pcd.empty ());

  // Two threads at work at once hold two detectors.
  std::atomic<int> inside{0};
  auto hold = [&] {
    kept.with ([&] (agex::BodyPartDetector<pcl::PointXYZ> &) {
      ++inside;
      for (int spin = 0; inside < 2 && spin < 2000; ++spin)
        std::this_thread::sleep_for (std::chrono::milliseconds (1));
      return 0;
    });
  };
  std::thread a (hold), b (hold);
  a.join ();
  b.join ();
  EXPECT_EQ (inside, 2);
  EXPECT_EQ (kept.size (), 2u);
}
}  // namespace
