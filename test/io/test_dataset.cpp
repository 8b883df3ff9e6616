// The agex dataset format (agex::Dataset, agex::DatasetWriter, labels.csv), the
// Bonn labels and the lifting of label pixels to 3D, agex::CoverageEvaluation,
// and the agex_convert and agex_eval executables as built, run on real Bonn frames.

#include "test_support.h"

#include <agex/detection/coverage_evaluation.h>
#include <agex/io/bonn.h>
#include <agex/io/dataset.h>
#include <agex/io/frame_io.h>

#include <pcl/io/pcd_io.h>

#include <nlohmann/json.hpp>

#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <iomanip>
#include <iterator>
#include <set>
#include <sstream>

#ifndef AGEX_CONVERT_EXECUTABLE
#error "AGEX_CONVERT_EXECUTABLE (the built agex_convert) must be defined"
#endif
#ifndef AGEX_EVAL_EXECUTABLE
#error "AGEX_EVAL_EXECUTABLE (the built agex_eval) must be defined"
#endif

namespace
{
using namespace agex_test;
using agex::BodyPart;
using agex::PartLabel;

// ---------------------------------------------------------------------------
// Helpers

std::string
readText (const fs::path &path)
{
  std::ifstream in (path);
  std::stringstream text;
  text << in.rdbuf ();
  return text.str ();
}

void
writeText (const fs::path &path, const std::string &text)
{
  std::ofstream out (path);
  out << text;
  ASSERT_TRUE (out.good ()) << path;
}

/** Replaces the first occurrence of from (which must be there) in the file. */
void
editText (const fs::path &path, const std::string &from, const std::string &to)
{
  std::string text = readText (path);
  const auto at = text.find (from);
  ASSERT_NE (at, std::string::npos) << "'" << from << "' not in " << path;
  text.replace (at, from.size (), to);
  writeText (path, text);
}

/** Runs fn, expects it to throw E, and every one of parts in the message. */
template <typename E = agex::DatasetError> void
expectThrowWith (const std::function<void ()> &fn, std::initializer_list<std::string> parts)
{
  try
  {
    fn ();
    ADD_FAILURE () << "no exception; expected one mentioning '" << *parts.begin () << "'";
  }
  catch (const E &e)
  {
    const std::string what = e.what ();
    for (const auto &part : parts)
      EXPECT_NE (what.find (part), std::string::npos) << "'" << part << "' not in the message: " << what;
  }
}

/** Entries of directory whose name starts with prefix (e.g. the writer's ".name.partial-"). */
std::vector<std::string>
entriesStartingWith (const fs::path &directory, const std::string &prefix)
{
  std::vector<std::string> found;
  for (const auto &entry : fs::directory_iterator (directory))
  {
    const std::string name = entry.path ().filename ().string ();
    if (name.rfind (prefix, 0) == 0)
      found.push_back (name);
  }
  return found;
}

/** Leftovers of any DatasetWriter in directory: staging (".*.partial-*") and old datasets. */
std::vector<std::string>
stagingLeftovers (const fs::path &directory)
{
  std::vector<std::string> found;
  for (const auto &entry : fs::directory_iterator (directory))
  {
    const std::string name = entry.path ().filename ().string ();
    if (!name.empty () && name[0] == '.' && name.find (".partial-") != std::string::npos)
      found.push_back (name);
  }
  return found;
}

std::string
joined (const std::vector<std::string> &names)
{
  std::string s;
  for (const auto &n : names)
    s += (s.empty () ? "" : ", ") + n;
  return s;
}

/** Runs a command line through the shell; its exit code (-1 if it did not exit). */
int
run (const std::string &command)
{
  const int status = std::system (command.c_str ());
  return status != -1 && WIFEXITED (status) ? WEXITSTATUS (status) : -1;
}

std::string
quoted (const std::string &s)
{
  return "'" + s + "'";
}

agex::DatasetInfo
smallInfo ()
{
  agex::DatasetInfo info;
  info.name = "unit-test";
  info.sensor = "sr4000";
  info.width = 4;
  info.height = 3;
  info.intrinsics.fx = 210.5;
  info.intrinsics.fy = 211.25;
  info.intrinsics.cx = 1.5;
  info.intrinsics.cy = 0.75;
  info.depth_scale = 0.016;
  info.provenance = "hand-built in test_dataset.cpp";
  return info;
}

/** A 4x3 organized cloud with NaN holes; seed varies the values. */
Cloud
smallCloud (int seed)
{
  Cloud cloud (4, 3, nanPoint ());
  cloud.is_dense = false;
  for (int v = 0; v < 3; ++v)
    for (int u = 0; u < 4; ++u)
    {
      if ((u + v + seed) % 5 == 0)
        continue;  // NaN
      const float z = 1.f + 0.1234567f * static_cast<float> (u + 4 * v + seed);
      cloud (u, v) = pcl::PointXYZ ((u - 1.5f) * z / 210.5f, (v - 0.75f) * z / 211.25f, z);
    }
  return cloud;
}

PartLabel
makeLabel (BodyPart part, int instance, const Eigen::Vector3f &tip, const Eigen::Vector3f &base,
           const Eigen::Vector2f &tip_px, const Eigen::Vector2f &base_px, bool visible, bool keyframe)
{
  PartLabel l;
  l.frame = "ignored-by-the-writer";
  l.part = part;
  l.instance = instance;
  l.tip = tip;
  l.base = base;
  l.tip_px = tip_px;
  l.base_px = base_px;
  l.visible = visible;
  l.keyframe = keyframe;
  return l;
}

const Eigen::Vector3f kNan3 = Eigen::Vector3f::Constant (std::numeric_limits<float>::quiet_NaN ());

/** Frames written in this order (not sorted by id) and their labels. */
struct SmallDataset
{
  std::vector<std::string> ids{"z-1", "a_0", "m.2"};
  std::vector<std::string> sequences{"seqB", "seqA", "seqB"};
  std::vector<Cloud> clouds{smallCloud (0), smallCloud (1), smallCloud (2)};
  std::vector<std::vector<PartLabel>> labels{
      {makeLabel (BodyPart::Head, 0, {0.125f, -0.75f, 2.345f}, kNan3, {1.5f, 0.25f}, {2.f, 1.f}, true, true),
       makeLabel (BodyPart::Hand, 1, {-0.3f, 0.1f, 2.5f}, {-0.2f, 0.05f, 2.4f}, {0.f, 2.f}, {3.f, 2.5f}, false, true)},
      {},
      {makeLabel (BodyPart::Foot, 0, {1.f / 3.f, 0.6180339887f, 2.7182818f}, {0.1f, 0.5f, 2.75f}, {3.25f, 2.75f},
                  {3.f, 1.5f}, true, false)}};

  void write (const std::string &directory, bool overwrite = false) const
  {
    agex::DatasetWriter writer (directory, smallInfo (), overwrite);
    for (std::size_t i = 0; i < ids.size (); ++i)
      writer.addFrame (ids[i], sequences[i], clouds[i], labels[i]);
    writer.commit ();
  }
};

/** A float that went through the CSV text (7 significant digits): exact when the
  * value has at most 7 significant digits, else within half a unit of the 7th. */
void
expectCsvFloat (float expected, float actual, const std::string &what)
{
  if (std::isnan (expected))
  {
    EXPECT_TRUE (std::isnan (actual)) << what;
    return;
  }
  std::ostringstream seven;
  seven << std::setprecision (7) << expected;
  if (std::stof (seven.str ()) == expected)
    EXPECT_EQ (bits (actual), bits (expected)) << what << ": " << seven.str () << " should read back bitwise";
  else
    EXPECT_NEAR (actual, expected, 6e-7 * std::abs (expected)) << what;
}

// ---------------------------------------------------------------------------
// 1. The dataset format

TEST (DatasetFormat, RoundTripKeepsInfoFramesLabelsAndClouds)
{
  TempDir tmp;
  const std::string dir = tmp.file ("small");
  const SmallDataset written;
  written.write (dir);

  const agex::Dataset ds = agex::Dataset::read (dir);
  const agex::DatasetInfo expected = smallInfo ();
  const agex::DatasetInfo &info = ds.info ();
  EXPECT_EQ (ds.directory (), dir);
  EXPECT_EQ (info.name, expected.name);
  EXPECT_EQ (info.sensor, expected.sensor);
  EXPECT_EQ (info.width, 4);
  EXPECT_EQ (info.height, 3);
  EXPECT_EQ (info.intrinsics.fx, expected.intrinsics.fx);
  EXPECT_EQ (info.intrinsics.fy, expected.intrinsics.fy);
  EXPECT_EQ (info.intrinsics.cx, expected.intrinsics.cx);
  EXPECT_EQ (info.intrinsics.cy, expected.intrinsics.cy);
  EXPECT_EQ (info.depth_scale, expected.depth_scale);
  EXPECT_EQ (info.units, "m");
  EXPECT_EQ (info.provenance, expected.provenance);

  // Frames in the order written, with their sequences.
  ASSERT_EQ (ds.frames ().size (), 3u);
  for (std::size_t i = 0; i < 3; ++i)
  {
    EXPECT_EQ (ds.frames ()[i].id, written.ids[i]);
    EXPECT_EQ (ds.frames ()[i].sequence, written.sequences[i]);
  }

  // Labels: per frame, in order, the frame id set by the writer.
  std::size_t total = 0;
  for (std::size_t f = 0; f < 3; ++f)
  {
    const std::vector<PartLabel> got = ds.labelsOf (written.ids[f]);
    ASSERT_EQ (got.size (), written.labels[f].size ()) << written.ids[f];
    total += got.size ();
    for (std::size_t j = 0; j < got.size (); ++j)
    {
      const PartLabel &a = written.labels[f][j], &b = got[j];
      const std::string what = written.ids[f] + " label " + std::to_string (j);
      EXPECT_EQ (b.frame, written.ids[f]) << what;
      EXPECT_EQ (b.part, a.part) << what;
      EXPECT_EQ (b.instance, a.instance) << what;
      EXPECT_EQ (b.visible, a.visible) << what;
      EXPECT_EQ (b.keyframe, a.keyframe) << what;
      for (int c = 0; c < 3; ++c)
      {
        expectCsvFloat (a.tip[c], b.tip[c], what + " tip[" + std::to_string (c) + "]");
        expectCsvFloat (a.base[c], b.base[c], what + " base[" + std::to_string (c) + "]");
      }
      for (int c = 0; c < 2; ++c)
      {
        expectCsvFloat (a.tip_px[c], b.tip_px[c], what + " tip_px");
        expectCsvFloat (a.base_px[c], b.base_px[c], what + " base_px");
      }
    }
  }
  EXPECT_EQ (ds.labels ().size (), total);
  EXPECT_TRUE (ds.isKeyframe ("z-1"));
  EXPECT_FALSE (ds.isKeyframe ("a_0")) << "no labels";
  EXPECT_FALSE (ds.isKeyframe ("m.2"));
  EXPECT_TRUE (ds.labelsOf ("no-such-frame").empty ());
  // The CSV really held a non-7-digit value (1/3) and a NaN base.
  EXPECT_NE (readText (fs::path (dir) / "labels.csv").find (",nan,nan,nan,"), std::string::npos);

  // Clouds: same size, NaN where they were NaN, the same bits elsewhere.
  for (std::size_t f = 0; f < 3; ++f)
  {
    SCOPED_TRACE (written.ids[f]);
    EXPECT_EQ (ds.framePath (written.ids[f]), (fs::path (dir) / "frames" / (written.ids[f] + ".pcd")).string ());
    const Cloud::Ptr cloud = ds.loadFrame (written.ids[f]);
    const Cloud &ref = written.clouds[f];
    ASSERT_EQ (cloud->width, ref.width);
    ASSERT_EQ (cloud->height, ref.height);
    ASSERT_EQ (cloud->size (), ref.size ());
    int nans = 0;
    for (std::size_t i = 0; i < ref.size (); ++i)
    {
      if (!isFinite (ref[i]))
      {
        ++nans;
        EXPECT_FALSE (isFinite ((*cloud)[i])) << "point " << i << " should be NaN";
        continue;
      }
      EXPECT_EQ (bits ((*cloud)[i].x), bits (ref[i].x)) << i;
      EXPECT_EQ (bits ((*cloud)[i].y), bits (ref[i].y)) << i;
      EXPECT_EQ (bits ((*cloud)[i].z), bits (ref[i].z)) << i;
    }
    EXPECT_GT (nans, 0) << "the fixture has NaN holes";
  }
}

TEST (DatasetFormat, LabelsCsvTextRoundTrip)
{
  // formatLabelsCsv -> file -> readLabelsCsv -> formatLabelsCsv gives the same text.
  TempDir tmp;
  const SmallDataset small;
  std::vector<PartLabel> labels;
  for (std::size_t f = 0; f < small.ids.size (); ++f)
    for (PartLabel l : small.labels[f])
    {
      l.frame = small.ids[f];
      labels.push_back (l);
    }
  const std::string text = agex::formatLabelsCsv (labels);
  writeText (tmp.file ("labels.csv"), text);
  const std::vector<PartLabel> read = agex::readLabelsCsv (tmp.file ("labels.csv"));
  ASSERT_EQ (read.size (), labels.size ());
  EXPECT_EQ (agex::formatLabelsCsv (read), text);
  // Blank lines and CRLF line ends are accepted.
  std::string crlf;
  for (const char c : text)
    crlf += c == '\n' ? std::string ("\r\n") : std::string (1, c);
  writeText (tmp.file ("crlf.csv"), crlf + "\r\n");
  EXPECT_EQ (agex::formatLabelsCsv (agex::readLabelsCsv (tmp.file ("crlf.csv"))), text);
}

// ---------------------------------------------------------------------------
// 2. DatasetWriter: refuses to replace without overwrite, all or nothing

TEST (DatasetWriter, ExistingDirectoryNeedsOverwrite)
{
  TempDir tmp;
  const fs::path dir = tmp.path () / "data";
  fs::create_directories (dir);
  writeText (dir / "precious.txt", "keep me");
  expectThrowWith ([&] { agex::DatasetWriter writer (dir.string (), smallInfo (), false); },
                   {dir.string (), "already exists", "--force"});
  EXPECT_EQ (readText (dir / "precious.txt"), "keep me") << "refused, so untouched";
  EXPECT_TRUE (stagingLeftovers (tmp.path ()).empty ()) << joined (stagingLeftovers (tmp.path ()));

  // Nor with overwrite: only an earlier agex dataset is replaced, never a directory of other
  // things, a regular file, or a dataset someone put a file of their own in.
  expectThrowWith ([&] { agex::DatasetWriter writer (dir.string (), smallInfo (), true); },
                   {dir.string (), "is a directory without an agex dataset.json", "only an earlier agex dataset"});
  EXPECT_EQ (readText (dir / "precious.txt"), "keep me");
  const fs::path file = tmp.path () / "notes.txt";
  writeText (file, "my notes");
  expectThrowWith ([&] { agex::DatasetWriter writer (file.string (), smallInfo (), true); },
                   {file.string (), "is a regular file, not an agex dataset"});
  EXPECT_EQ (readText (file), "my notes");
  fs::remove (file);
  fs::remove (dir / "precious.txt");
  writeText (dir / "dataset.json", "{\"format\": \"something-else\"}");
  expectThrowWith ([&] { agex::DatasetWriter writer (dir.string (), smallInfo (), true); },
                   {dir.string (), "without an agex dataset.json"});
  fs::remove_all (dir);

  SmallDataset small;
  small.write (dir.string ());
  writeText (dir / "precious.txt", "keep me");
  expectThrowWith ([&] { agex::DatasetWriter writer (dir.string (), smallInfo (), true); },
                   {dir.string (), "holds precious.txt, which is not part of an agex dataset"});
  EXPECT_EQ (readText (dir / "precious.txt"), "keep me");
  fs::remove (dir / "precious.txt");
  writeText (dir / "frames" / "mine.txt", "keep me");
  expectThrowWith ([&] { agex::DatasetWriter writer (dir.string (), smallInfo (), true); },
                   {dir.string (), "holds frames/mine.txt"});
  fs::remove (dir / "frames" / "mine.txt");
  // An earlier dataset is replaced by the new one, here by a dataset of one frame.
  small.ids.resize (1);
  small.write (dir.string (), true);
  EXPECT_EQ (agex::Dataset::read (dir.string ()).frames ().size (), 1u);
  const auto entries = std::distance (fs::directory_iterator (tmp.path ()), fs::directory_iterator ());
  EXPECT_EQ (entries, 1) << "only the dataset, no staging or old copy: " << joined (stagingLeftovers (tmp.path ()));
}

TEST (DatasetWriter, WithoutCommitNothingIsLeftBehind)
{
  TempDir tmp;
  const fs::path dir = tmp.path () / "never";
  {
    agex::DatasetWriter writer (dir.string (), smallInfo ());
    writer.addFrame ("f0", "s", smallCloud (0), {});
    // While it works, the dataset is staged beside the target, not in it.
    EXPECT_EQ (entriesStartingWith (tmp.path (), ".never.partial-").size (), 1u);
    EXPECT_FALSE (fs::exists (dir));
  }
  EXPECT_FALSE (fs::exists (dir));
  EXPECT_TRUE (stagingLeftovers (tmp.path ()).empty ()) << joined (stagingLeftovers (tmp.path ()));

  // Nor does a writer abandoned after an error, and an existing dataset it was
  // to replace stays as it was.
  const fs::path existing = tmp.path () / "existing";
  SmallDataset small;
  small.write (existing.string ());
  const std::string json = readText (existing / "dataset.json");
  {
    agex::DatasetWriter writer (existing.string (), smallInfo (), true);
    writer.addFrame ("f0", "s", smallCloud (0), {});
    EXPECT_THROW (writer.addFrame ("f0", "s", smallCloud (1), {}), agex::DatasetError) << "duplicate id";
    EXPECT_THROW (writer.addFrame ("a/b", "s", smallCloud (1), {}), agex::DatasetError) << "bad id";
    EXPECT_THROW (writer.addFrame ("f1", "s", Cloud (5, 3, pcl::PointXYZ ()), {}), agex::DatasetError)
        << "wrong size";
  }
  EXPECT_EQ (readText (existing / "dataset.json"), json);
  EXPECT_EQ (agex::Dataset::read (existing.string ()).frames ().size (), 3u);
  EXPECT_TRUE (stagingLeftovers (tmp.path ()).empty ()) << joined (stagingLeftovers (tmp.path ()));
}

TEST (DatasetWriter, AKilledWritersLeftoversAreCleanedAndItsMovedAsideDatasetRestored)
{
  // A writer killed with SIGKILL runs no destructor: its staging directory stays.
  TempDir tmp;
  const fs::path dir = tmp.path () / "killed";
  const pid_t child = ::fork ();
  ASSERT_GE (child, 0);
  if (child == 0)
  {
    agex::DatasetWriter writer (dir.string (), smallInfo ());
    writer.addFrame ("f0", "s", smallCloud (0), {});
    ::raise (SIGKILL);
  }
  int status = 0;
  ASSERT_EQ (::waitpid (child, &status, 0), child);
  ASSERT_TRUE (WIFSIGNALED (status));
  const auto left = entriesStartingWith (tmp.path (), ".killed.partial-" + std::to_string (child) + "-");
  ASSERT_EQ (left.size (), 1u) << "the killed writer's staging directory, named with its pid";

  // Killed inside commit (), after moving the previous dataset aside: simulated by
  // moving a real dataset to the name commit () gives it.
  SmallDataset small;
  small.write (dir.string ());
  const std::string json = readText (dir / "dataset.json");
  fs::rename (dir, tmp.path () / (left[0] + ".old"));

  // The next writer of that target cleans up: the staging directory goes, the
  // dataset comes back, and the new writer proceeds as usual.
  {
    agex::DatasetWriter writer (dir.string (), smallInfo (), true);
    EXPECT_EQ (readText (dir / "dataset.json"), json) << "the moved-aside dataset is back in place";
    EXPECT_EQ (entriesStartingWith (tmp.path (), ".killed.partial-" + std::to_string (child) + "-").size (), 0u);
  }
  EXPECT_EQ (readText (dir / "dataset.json"), json);
  EXPECT_TRUE (stagingLeftovers (tmp.path ()).empty ()) << joined (stagingLeftovers (tmp.path ()));
}

// ---------------------------------------------------------------------------
// 3. Bad dataset files: the error names the file (and the line)

class BadDataset : public ::testing::Test
{
protected:
  void SetUp () override { SmallDataset ().write (dir ()); }
  std::string dir () const { return tmp_.file ("bad"); }
  fs::path json () const { return fs::path (dir ()) / "dataset.json"; }
  fs::path csv () const { return fs::path (dir ()) / "labels.csv"; }
  void expectReadFails (std::initializer_list<std::string> parts)
  {
    expectThrowWith ([&] { agex::Dataset::read (dir ()); }, parts);
  }
  /** Appends a labels.csv row (15 fields). */
  void appendRow (const std::string &row)
  {
    std::ofstream out (csv (), std::ios::app);
    out << row << "\n";
  }

private:
  TempDir tmp_;
};

TEST_F (BadDataset, Control) { EXPECT_NO_THROW (agex::Dataset::read (dir ())); }

TEST_F (BadDataset, MissingDatasetJson)
{
  fs::remove (json ());
  expectReadFails ({json ().string (), "missing"});
  expectThrowWith ([&] { agex::Dataset::read (dir () + "/nope"); }, {dir () + "/nope", "not a dataset directory"});
}

TEST_F (BadDataset, InvalidJson)
{
  editText (json (), "\"frames\"", "frames");
  expectReadFails ({json ().string (), "not valid JSON"});
}

TEST_F (BadDataset, WrongFormatOrVersion)
{
  editText (json (), "\"version\": 1", "\"version\": 2");
  expectReadFails ({json ().string (), "version 2", "not supported", "version 1"});
  editText (json (), "\"version\": 2", "\"version\": \"1\"");
  expectReadFails ({json ().string (), "'version'", "wrong type"});
  editText (json (), "\"version\": \"1\"", "\"version\": 1");
  editText (json (), "\"agex-dataset\"", "\"other-format\"");
  expectReadFails ({json ().string (), "'format'", "agex-dataset"});
}

TEST_F (BadDataset, MissingFieldOrBadIntrinsics)
{
  editText (json (), "\"sensor\"", "\"sensr\"");
  expectReadFails ({json ().string (), "missing field 'sensor'"});
  editText (json (), "\"sensr\"", "\"sensor\"");
  editText (json (), "\"fx\": 210.5", "\"fx\": -1");
  expectReadFails ({json ().string (), "fx"});
}

TEST_F (BadDataset, LabelsWrongHeader)
{
  editText (csv (), "tip_x,tip_y", "tipx,tip_y");
  expectReadFails ({csv ().string () + ":1:", "header"});
}

TEST_F (BadDataset, LabelsBadNumberNamesTheLine)
{
  // Line 3 is the second label (z-1 hand 1); its tip_y is 0.1.
  editText (csv (), "hand,1,-0.3,0.1,", "hand,1,-0.3,0.1x,");
  expectReadFails ({csv ().string () + ":3:", "tip_y", "0.1x"});
}

TEST_F (BadDataset, LabelsNanPixelOrBadFlag)
{
  editText (csv (), "hand,1,-0.3,0.1,2.5,-0.2,0.05,2.4,0,2,", "hand,1,-0.3,0.1,2.5,-0.2,0.05,2.4,nan,2,");
  expectReadFails ({csv ().string () + ":3:", "tip_u"});
  editText (csv (), "2.4,nan,2,", "2.4,0,2,");
  editText (csv (), "3,2.5,0,1", "3,2.5,yes,1");
  expectReadFails ({csv ().string () + ":3:", "visible"});
}

TEST_F (BadDataset, LabelsWrongFieldCount)
{
  appendRow ("m.2,hand,0,1,2,3");
  expectReadFails ({csv ().string () + ":5:", "15", "found 6"});
}

TEST_F (BadDataset, LabelsUnknownPart)
{
  editText (csv (), "z-1,head,0,", "z-1,knee,0,");
  expectReadFails ({csv ().string () + ":2:", "unknown part 'knee'"});
}

TEST_F (BadDataset, LabelsDuplicate)
{
  appendRow ("z-1,hand,1,0,0,2,0,0,2,1,1,1,1,1,0");
  expectReadFails ({csv ().string () + ":5:", "duplicate", "z-1"});
}

TEST_F (BadDataset, LabelForAnUnlistedFrame)
{
  appendRow ("ghost,head,0,0,0,2,0,0,2,1,1,1,1,1,0");
  // The message names the file and the frame (not the line: the check runs
  // after the file is parsed).
  expectReadFails ({csv ().string (), "'ghost'", "does not list"});
}

TEST_F (BadDataset, ListedFrameWithoutItsPcd)
{
  const std::string pcd = (fs::path (dir ()) / "frames" / "a_0.pcd").string ();
  fs::remove (pcd);
  expectReadFails ({pcd, "listed in dataset.json but missing"});
}

TEST_F (BadDataset, FrameOfTheWrongSize)
{
  // Readable, but loadFrame checks the size against dataset.json.
  const std::string pcd = (fs::path (dir ()) / "frames" / "m.2.pcd").string ();
  ASSERT_EQ (pcl::io::savePCDFileBinary (pcd, Cloud (5, 3, pcl::PointXYZ (0.f, 0.f, 1.f))), 0);
  const agex::Dataset ds = agex::Dataset::read (dir ());
  expectThrowWith<agex::FrameError> ([&] { ds.loadFrame ("m.2"); }, {pcd, "5x3", "4x3"});
}

TEST_F (BadDataset, LabelsVisibleWithoutATip)
{
  // Line 2 (z-1 head 0) is visible: a NaN tip there is refused, as an inf is; marked
  // invisible, the same label is fine.
  editText (csv (), "z-1,head,0,0.125,-0.75,2.345,", "z-1,head,0,nan,nan,nan,");
  expectReadFails ({csv ().string () + ":2:", "visible is 1 but the tip is not a number"});
  editText (csv (), "z-1,head,0,nan,nan,nan,", "z-1,head,0,0.125,inf,2.345,");
  expectReadFails ({csv ().string () + ":2:", "tip_y"});
  editText (csv (), "z-1,head,0,0.125,inf,2.345,", "z-1,head,0,0.125,nan,2.345,");
  expectReadFails ({csv ().string () + ":2:", "visible is 1"});
  std::string text = readText (csv ());
  const std::size_t row = text.find ("z-1,head,0,0.125,nan,2.345,");
  ASSERT_NE (row, std::string::npos);
  const std::size_t end = text.find ('\n', row);
  ASSERT_EQ (text.substr (end - 4, 4), ",1,1");
  text.replace (end - 4, 4, ",0,1");
  writeText (csv (), text);
  EXPECT_NO_THROW (agex::Dataset::read (dir ()));
}

TEST_F (BadDataset, FifosInPlaceOfItsFilesAreRefusedWithoutBlocking)
{
  fs::remove (csv ());
  ASSERT_EQ (::mkfifo (csv ().c_str (), 0600), 0);
  expectReadFails ({csv ().string (), "is a FIFO (named pipe), not a regular file"});
  fs::remove (json ());
  ASSERT_EQ (::mkfifo (json ().c_str (), 0600), 0);
  expectReadFails ({json ().string (), "FIFO"});
  expectThrowWith ([&] { agex::readBonnLabels (csv ().string ()); }, {csv ().string (), "FIFO"});
}

TEST (DatasetReplacement, OnlyAnEarlierDatasetOfItsOwnFilesMayBeReplaced)
{
  TempDir tmp;
  const std::string ds = tmp.file ("ds");
  SmallDataset ().write (ds);
  EXPECT_EQ (agex::datasetReplaceProblem (ds), "");
  EXPECT_EQ (agex::datasetReplaceProblem (tmp.file ("missing")), "") << "nothing to lose";
  // Recognised by content, not by name.
  const std::string file = tmp.file ("dataset.json");
  writeText (file, readText (fs::path (ds) / "dataset.json"));
  EXPECT_NE (agex::datasetReplaceProblem (file).find ("is a regular file, not an agex dataset"), std::string::npos);
  const std::string other = tmp.file ("other");
  fs::create_directories (other);
  EXPECT_NE (agex::datasetReplaceProblem (other).find ("without an agex dataset.json"), std::string::npos);
  writeText (fs::path (other) / "dataset.json", "{\"format\": \"agex-dataset\"");  // cut: not JSON
  EXPECT_NE (agex::datasetReplaceProblem (other).find ("without an agex dataset.json"), std::string::npos);
  fs::create_directories (fs::path (ds) / "frames" / "sub");
  EXPECT_NE (agex::datasetReplaceProblem (ds).find ("holds frames/sub"), std::string::npos);
  fs::remove (fs::path (ds) / "frames" / "sub");
  // A dataset with per-pixel part and person images (agex_synth's) is all its own files.
  const std::string labelled = tmp.file ("labelled");
  {
    agex::DatasetInfo info = smallInfo ();
    info.part_labels = {{1, "head"}};
    agex::DatasetWriter writer (labelled, info);
    writer.addFrame ("f0", "s", smallCloud (0), {});
    writer.addPartLabels ("f0", cv::Mat (info.height, info.width, CV_8UC1, cv::Scalar (1)));
    writer.addPersonLabels ("f0", cv::Mat (info.height, info.width, CV_8UC1, cv::Scalar (1)));
    writer.commit ();
  }
  ASSERT_TRUE (fs::exists (fs::path (labelled) / "labels" / "f0.png"));
  ASSERT_TRUE (fs::exists (fs::path (labelled) / "persons" / "f0.png"));
  EXPECT_EQ (agex::datasetReplaceProblem (labelled), "");
  EXPECT_EQ (fs::path (agex::enclosingDataset (labelled + "/labels/f0.png")), fs::canonical (labelled));
  writeText (fs::path (labelled) / "persons" / "notes.txt", "mine");
  EXPECT_NE (agex::datasetReplaceProblem (labelled).find ("holds persons/notes.txt"), std::string::npos);
  fs::create_symlink (ds, tmp.file ("link"));
  EXPECT_NE (agex::datasetReplaceProblem (tmp.file ("link")).find ("symbolic link"), std::string::npos);

  // The dataset a file belongs to.
  EXPECT_EQ (fs::path (agex::enclosingDataset (ds + "/frames/a_0.pcd")), fs::canonical (ds));
  EXPECT_EQ (fs::path (agex::enclosingDataset (ds + "/labels.csv")), fs::canonical (ds));
  EXPECT_EQ (agex::enclosingDataset (ds + "/frames/a_0.png"), "");
  EXPECT_EQ (agex::enclosingDataset (tmp.file ("notes.txt")), "");
}

TEST (DatasetWriter, SequenceNamesAreKeptExactlyOrRefused)
{
  EXPECT_TRUE (agex::validSequenceName ("s\xc3\xa9q"));   // séq
  EXPECT_TRUE (agex::validSequenceName ("s\xc3\xa8q"));   // sèq
  EXPECT_TRUE (agex::validSequenceName ("take 1"));
  EXPECT_TRUE (agex::validSequenceName (""));
  std::string why;
  EXPECT_FALSE (agex::validSequenceName ("s\xe9q", &why));  // Latin-1, not UTF-8
  EXPECT_EQ (why, "is not valid UTF-8");
  EXPECT_FALSE (agex::validSequenceName ("\xc0\xaf"));      // an overlong '/'
  EXPECT_FALSE (agex::validSequenceName ("\xed\xa0\x80"));  // a surrogate
  EXPECT_FALSE (agex::validSequenceName ("a,b", &why));
  EXPECT_NE (why.find ("separates sequences"), std::string::npos);
  EXPECT_FALSE (agex::validSequenceName ("a@b"));
  EXPECT_FALSE (agex::validSequenceName ("a\tb"));

  TempDir tmp;
  {
    agex::DatasetWriter writer (tmp.file ("utf"), smallInfo ());
    writer.addFrame ("a", "s\xc3\xa9q", smallCloud (0), {});
    writer.addFrame ("b", "s\xc3\xa8q", smallCloud (1), {});
    EXPECT_THROW (writer.addFrame ("c", "a,b", smallCloud (2), {}), agex::DatasetError);
    // A visible label needs a tip: the reader would refuse the file otherwise.
    EXPECT_THROW (writer.addFrame ("d", "s", smallCloud (2),
                                   {makeLabel (BodyPart::Head, 0, kNan3, kNan3, {1.f, 1.f}, {1.f, 1.f}, true, true)}),
                  agex::DatasetError);
    writer.commit ();
  }
  const agex::Dataset ds = agex::Dataset::read (tmp.file ("utf"));
  ASSERT_EQ (ds.frames ().size (), 2u);
  EXPECT_EQ (ds.frames ()[0].sequence, "s\xc3\xa9q");
  EXPECT_EQ (ds.frames ()[1].sequence, "s\xc3\xa8q");
}

// ---------------------------------------------------------------------------
// 4. The Bonn labels and lifting a label pixel to 3D

TEST (BonnLabels, ReadsEveryRowOfTheRealFile)
{
  const std::string csv = sharedData ("bonn/labels.csv");
  AGEX_REQUIRE_BONN (csv);
  std::ifstream in (csv);
  std::size_t lines = 0;
  for (std::string line; std::getline (in, line);)
    lines += !line.empty ();
  const std::vector<agex::BonnLabel> labels = agex::readBonnLabels (csv);
  EXPECT_EQ (labels.size (), lines - 1) << "every line but the header is a label";
  std::size_t heads = 0, keyframes = 0;
  for (const auto &l : labels)
  {
    heads += l.part == BodyPart::Head;
    keyframes += l.keyframe;
    EXPECT_TRUE (l.tip_px.x () >= 0.f && l.tip_px.x () < 640.f && l.tip_px.y () >= 0.f && l.tip_px.y () < 480.f)
        << l.sequence << "/" << l.frame;
  }
  EXPECT_GT (heads, 100u);
  EXPECT_GT (keyframes, 0u);
  EXPECT_LT (keyframes, labels.size ());
}

TEST (BonnLabels, MalformedFilesNamePathAndLine)
{
  TempDir tmp;
  const std::string header = "sequence,frame,keyframe,part,instance,tip_u,tip_v,base_u,base_v\n";
  const std::string good = "1,002,1,head,0,330,35,330,90\n";
  struct Case
  {
    std::string text, where, what;
  };
  const std::vector<Case> cases = {
      {"sequence,frame,part\n" + good, ":1:", "header"},
      {header + good + "1,003,2,head,0,330,35,330,90\n", ":3:", "keyframe"},
      {header + good + good + "1,004,0,knee,0,330,35,330,90\n", ":4:", "unknown part 'knee'"},
      {header + "1,002,1,head,0,33O,35,330,90\n", ":2:", "33O"},
      {header + good + "\n1,002,1,hand,0,1,2\n", ":4:", "9 fields"},
      {header + "1,002,1,hand,-1,1,2,3,4\n", ":2:", "instance"},
  };
  for (std::size_t i = 0; i < cases.size (); ++i)
  {
    SCOPED_TRACE ("case " + std::to_string (i));
    const std::string path = tmp.file ("labels" + std::to_string (i) + ".csv");
    writeText (path, cases[i].text);
    expectThrowWith ([&] { agex::readBonnLabels (path); }, {path + cases[i].where, cases[i].what});
  }
  expectThrowWith ([&] { agex::readBonnLabels (tmp.file ("absent.csv")); }, {tmp.file ("absent.csv")});
  writeText (tmp.file ("ok.csv"), header + good + good);
  EXPECT_EQ (agex::readBonnLabels (tmp.file ("ok.csv")).size (), 2u);
}

/** 20x20: a background wall at 3 m, a foreground square at 2 m in columns and rows 8..11. */
Cloud::Ptr
wallAndSquare ()
{
  Camera cam;
  cam.width = cam.height = 20;
  cam.cx = cam.cy = 9.5;
  Cloud::Ptr cloud = nanCloud (20, 20);
  for (int v = 0; v < 20; ++v)
    for (int u = 0; u < 20; ++u)
      (*cloud) (u, v) = rayPoint (cam, u, v, u >= 8 && u <= 11 && v >= 8 && v <= 11 ? 2.0 : 3.0);
  return cloud;
}

TEST (LiftPixelToSurface, LabelOnTheBackgroundTakesTheNearestForegroundPoint)
{
  const Cloud::Ptr cloud = wallAndSquare ();
  Eigen::Vector3f point;
  Eigen::Vector2i pixel (-1, -1);
  // (6, 9.6) is on the wall, two pixels left of the square; the window (radius 3)
  // reaches columns 8 and 9 of the square, whose nearest pixel is (8, 10).
  ASSERT_TRUE (agex::liftPixelToSurface (*cloud, 6.f, 9.6f, 3, 0.05f, point, &pixel));
  EXPECT_EQ (pixel, Eigen::Vector2i (8, 10));
  EXPECT_EQ (point, (*cloud) (8, 10).getVector3fMap ());
  EXPECT_FLOAT_EQ (point.z (), 2.f) << "the foreground, not the wall";
  // No out parameter needed.
  ASSERT_TRUE (agex::liftPixelToSurface (*cloud, 6.f, 9.6f, 3, 0.05f, point));
  EXPECT_EQ (point, (*cloud) (8, 10).getVector3fMap ());

  // Controls: a window that does not reach the square is all wall, the wall is
  // then the foreground and the labelled pixel itself wins; a depth band wider
  // than the 1 m step makes the wall foreground too.
  ASSERT_TRUE (agex::liftPixelToSurface (*cloud, 6.f, 9.6f, 1, 0.05f, point, &pixel));
  EXPECT_EQ (pixel, Eigen::Vector2i (6, 10));
  ASSERT_TRUE (agex::liftPixelToSurface (*cloud, 6.f, 9.6f, 3, 1.5f, point, &pixel));
  EXPECT_EQ (pixel, Eigen::Vector2i (6, 10));
  // On the square, the labelled pixel itself.
  ASSERT_TRUE (agex::liftPixelToSurface (*cloud, 10.2f, 8.9f, 6, 0.05f, point, &pixel));
  EXPECT_EQ (pixel, Eigen::Vector2i (10, 9));
  // A NaN hole under the label: the nearest finite foreground pixel around it.
  (*cloud) (10, 9) = nanPoint ();
  ASSERT_TRUE (agex::liftPixelToSurface (*cloud, 10.2f, 8.9f, 6, 0.05f, point, &pixel));
  EXPECT_EQ (pixel, Eigen::Vector2i (11, 9)) << "0.65 px squared away, (10, 8) is 0.85";
}

TEST (LiftPixelToSurface, NoFinitePointInTheWindowGivesFalse)
{
  Cloud::Ptr cloud = wallAndSquare ();
  for (int v = 0; v < 20; ++v)
    for (int u = 0; u < 10; ++u)
      (*cloud) (u, v) = nanPoint ();  // the left half is NaN
  Eigen::Vector3f point (7.f, 7.f, 7.f);
  EXPECT_FALSE (agex::liftPixelToSurface (*cloud, 3.f, 10.f, 6, 0.05f, point)) << "columns 0..9 are all NaN";
  EXPECT_TRUE (agex::liftPixelToSurface (*cloud, 3.f, 10.f, 7, 0.05f, point)) << "column 10 is in reach";
  EXPECT_FALSE (agex::liftPixelToSurface (*nanCloud (20, 20), 10.f, 10.f, 6, 0.05f, point));
  EXPECT_FALSE (agex::liftPixelToSurface (*cloud, -30.f, 10.f, 6, 0.05f, point)) << "window outside the image";
  EXPECT_FALSE (agex::liftPixelToSurface (*cloud, nanf_ (), 10.f, 6, 0.05f, point));
  Cloud flat;
  flat.push_back (pcl::PointXYZ (0.f, 0.f, 2.f));
  EXPECT_FALSE (agex::liftPixelToSurface (flat, 0.f, 0.f, 6, 0.05f, point)) << "unorganized";
}

// ---------------------------------------------------------------------------
// 5. CoverageEvaluation on hand-built points and labels

agex::InterestPoint
interestPoint (int mesh, int rank, const Eigen::Vector3f &p, const Eigen::Vector3f &orientation)
{
  agex::InterestPoint q;
  q.getVector3fMap () = p;
  q.getOrientationVector3fMap () = orientation;
  q.mesh = mesh;
  q.rank = rank;
  return q;
}

PartLabel
scored (BodyPart part, int instance, const Eigen::Vector3f &tip, const Eigen::Vector3f &base, bool visible = true)
{
  PartLabel l = makeLabel (part, instance, tip, base, {0.f, 0.f}, {0.f, 0.f}, visible, true);
  l.frame = "f";
  return l;
}

TEST (CoverageEvaluation, CountsExtremaAfterTheCentroid)
{
  const Eigen::Vector3f up (0.f, -1.f, 0.f), down (0.f, 1.f, 0.f), right (1.f, 0.f, 0.f);
  pcl::PointCloud<agex::InterestPoint> points;
  // Mesh 0: the centroid (rank 1), then extrema 1..4 (ranks 2..5).
  points.push_back (interestPoint (0, 1, {0.f, 0.f, 2.f}, Eigen::Vector3f::Zero ()));
  points.push_back (interestPoint (0, 2, {0.f, -0.8f, 2.f}, up));     // extremum 1: the head
  points.push_back (interestPoint (0, 3, {0.1f, 0.8f, 2.f}, down));   // extremum 2: foot 0
  points.push_back (interestPoint (0, 4, {0.5f, 0.f, 2.f}, down));    // extremum 3: hand 0, orientation off by 90
  points.push_back (interestPoint (0, 5, {-0.6f, -0.6f, 2.f}, up));   // extremum 4: beyond max_k, nothing near
  // Mesh 1: its own centroid and first extremum (near foot 1).
  points.push_back (interestPoint (1, 1, {-0.5f, 0.5f, 2.f}, Eigen::Vector3f::Zero ()));
  points.push_back (interestPoint (1, 2, {-0.1f, 0.9f, 2.f}, down));

  const float c30 = std::cos (static_cast<float> (M_PI / 6)), s30 = 0.5f;
  const Eigen::Vector3f foot0_tip (0.1f, 0.85f, 2.f);
  std::vector<PartLabel> labels = {
      scored (BodyPart::Head, 0, {0.f, -0.85f, 2.f}, {0.f, -0.6f, 2.f}),                       // 5 cm from extremum 1, 0 deg
      scored (BodyPart::Foot, 0, foot0_tip, foot0_tip - 0.2f * Eigen::Vector3f (s30, c30, 0.f)),  // extremum 2, 30 deg
      scored (BodyPart::Foot, 1, {-0.1f, 0.85f, 2.f}, {-0.1f, 0.6f, 2.f}),                    // mesh 1's extremum 1, 0 deg
      scored (BodyPart::Hand, 0, {0.55f, 0.f, 2.f}, {0.35f, 0.f, 2.f}),                       // extremum 3, 90 deg
      scored (BodyPart::Hand, 1, {0.02f, 0.f, 2.f}, {0.02f, -0.2f, 2.f}),                     // only the centroid is near
      // Not scored: invisible, NaN tip.
      scored (BodyPart::Head, 1, {0.f, -0.8f, 2.f}, {0.f, -0.6f, 2.f}, false),
      scored (BodyPart::Foot, 2, kNan3, {0.f, 0.f, 2.f}),
  };

  agex::CoverageEvaluation eval (3, 0.10f);
  eval.addFrame (points, labels);
  eval.addFrame (points, {});  // a frame without labels counts as a frame, nothing else
  EXPECT_EQ (eval.frames (), 2);
  EXPECT_EQ (eval.labelCount (BodyPart::Head), 1u) << "the invisible head is not scored";
  EXPECT_EQ (eval.labelCount (BodyPart::Foot), 2u) << "the NaN tip is not scored";
  EXPECT_EQ (eval.labelCount (BodyPart::Hand), 2u);

  // Extrema: head at k >= 1; feet 1/2 at k = 1 (mesh 1), both at k = 2; hands
  // 1/2 at k = 3 (the centroid never covers anything).
  EXPECT_DOUBLE_EQ (eval.coverage (BodyPart::Head, 1), 1.0);
  EXPECT_DOUBLE_EQ (eval.coverage (BodyPart::Foot, 1), 0.5);
  EXPECT_DOUBLE_EQ (eval.coverage (BodyPart::Foot, 2), 1.0);
  for (const auto part : {BodyPart::Head, BodyPart::Hand, BodyPart::Foot})
    for (int k : {1, 2, 5})
      EXPECT_DOUBLE_EQ (static_cast<double> (eval.coveredCount (part, k)),
                        eval.coverage (part, k) * static_cast<double> (eval.labelCount (part)));
  EXPECT_DOUBLE_EQ (eval.coverage (BodyPart::Hand, 1), 0.0);
  EXPECT_DOUBLE_EQ (eval.coverage (BodyPart::Hand, 2), 0.0);
  EXPECT_DOUBLE_EQ (eval.coverage (BodyPart::Hand, 3), 0.5);
  // Counting the centroid, k is the first k points: ranks 1..k.
  EXPECT_DOUBLE_EQ (eval.coverageCountingCentroid (BodyPart::Head, 1), 0.0);
  EXPECT_DOUBLE_EQ (eval.coverageCountingCentroid (BodyPart::Head, 2), 1.0);
  EXPECT_DOUBLE_EQ (eval.coverageCountingCentroid (BodyPart::Foot, 2), 0.5) << "mesh 1's rank 2";
  EXPECT_DOUBLE_EQ (eval.coverageCountingCentroid (BodyPart::Foot, 3), 1.0);
  EXPECT_DOUBLE_EQ (eval.coverageCountingCentroid (BodyPart::Hand, 1), 0.5) << "hand 1 at the centroid";
  EXPECT_DOUBLE_EQ (eval.coverageCountingCentroid (BodyPart::Hand, 3), 0.5) << "hand 0 is rank 4 > max_k";

  // Orientation: between the covering extremum's orientation and tip - base.
  EXPECT_NEAR (eval.orientationMedianDeg (BodyPart::Head), 0.0, 1e-3);
  EXPECT_NEAR (eval.orientationMedianDeg (BodyPart::Foot), 15.0, 1e-3) << "median of 30 and 0";
  EXPECT_NEAR (eval.orientationMedianDeg (BodyPart::Hand), 90.0, 1e-3);

  const nlohmann::json report = eval.report (2);
  EXPECT_EQ (report["frames"], 2);
  EXPECT_EQ (report["k"], 2);
  EXPECT_DOUBLE_EQ (report["coverage"]["foot"].get<double> (), 1.0);
  EXPECT_DOUBLE_EQ (report["coverage"]["hand"].get<double> (), 0.0);
  EXPECT_EQ (report["coverage_curve"]["hand"], nlohmann::json::array ({0.0, 0.0, 0.5}));
  EXPECT_DOUBLE_EQ (report["first_rank_median"]["foot"].get<double> (), 1.5);
  EXPECT_DOUBLE_EQ (report["first_rank_median"]["hand"].get<double> (), 3.0);
  EXPECT_EQ (report["never_found_within_k"]["hand"], 1);
  EXPECT_EQ (report["labels"]["head"], 1);
  ASSERT_EQ (eval.details ().size (), 5u) << "one entry per scored label";
  EXPECT_EQ (eval.details ()[0]["first_extremum"], 1);
  EXPECT_EQ (eval.details ()[4]["first_extremum"], 0);
}

TEST (CoverageEvaluation, NothingScoredGivesNaNAndNull)
{
  agex::CoverageEvaluation eval (5, 0.1f);
  eval.addFrame (pcl::PointCloud<agex::InterestPoint> (), {scored (BodyPart::Head, 0, {0.f, 0.f, 2.f}, kNan3)});
  EXPECT_DOUBLE_EQ (eval.coverage (BodyPart::Head, 5), 0.0) << "a label and no points: not covered";
  EXPECT_TRUE (std::isnan (eval.coverage (BodyPart::Hand, 5))) << "no hand labels";
  EXPECT_TRUE (std::isnan (eval.orientationMedianDeg (BodyPart::Head)));
  const nlohmann::json report = eval.report (5);
  EXPECT_TRUE (report["coverage"]["hand"].is_null ());
  EXPECT_TRUE (report["orientation_median_deg"]["head"].is_null ());
  // Counts stay whole numbers, 0 for a class without labels.
  EXPECT_EQ (eval.coveredCount (BodyPart::Head, 5), 0u);
  EXPECT_EQ (eval.coveredCount (BodyPart::Hand, 5), 0u);
}

// ---------------------------------------------------------------------------
// 6. agex_convert and agex_eval, as built, on Bonn sequence 1 (33 frames)

class BonnConversion : public ::testing::Test
{
protected:
  static std::string bonn () { return sharedData ("bonn"); }
  std::string dataset () const { return tmp_.file ("bonn1"); }
  std::string log () const { return tmp_.file ("log.txt"); }
  int convert (const std::string &extra)
  {
    return run (quoted (AGEX_CONVERT_EXECUTABLE) + " bonn --input " + quoted (bonn ()) + " --sequences 1 --output " +
                quoted (dataset ()) + " " + extra + " >> " + quoted (log ()) + " 2>&1");
  }
  void SetUp () override
  {
    AGEX_REQUIRE_BONN (bonn () + "/labels.csv");
    AGEX_REQUIRE_BONN (bonn () + "/depth/1/000.png");
    ASSERT_EQ (convert (""), 0) << readText (log ());
  }
  TempDir tmp_;
};

TEST_F (BonnConversion, PortraitFramesAndLabelsOnTheBody)
{
  const agex::Dataset ds = agex::Dataset::read (dataset ());
  const agex::DatasetInfo &info = ds.info ();
  EXPECT_EQ (info.width, 144);
  EXPECT_EQ (info.height, 176);
  EXPECT_NEAR (info.intrinsics.fx, 210.0, 1e-9) << "525 x 0.4";
  EXPECT_NEAR (info.intrinsics.fy, 210.0, 1e-9);
  EXPECT_NEAR (info.intrinsics.cx, 71.5, 1e-9) << "0.4 (319.5 - 140 + 0.5) - 0.5";
  EXPECT_NEAR (info.intrinsics.cy, 87.5, 1e-9) << "0.4 (239.5 - 20 + 0.5) - 0.5";
  EXPECT_DOUBLE_EQ (info.depth_scale, 0.016);
  ASSERT_EQ (ds.frames ().size (), 33u);
  EXPECT_EQ (ds.frames ().front ().id, "1_000");
  EXPECT_EQ (ds.frames ().back ().id, "1_032");
  for (const auto &f : ds.frames ())
    EXPECT_EQ (f.sequence, "1");

  // Every Bonn row of sequence 1 is a label, keyframes as in the source.
  std::size_t rows = 0, key_rows = 0;
  for (const auto &l : agex::readBonnLabels (bonn () + "/labels.csv"))
    if (l.sequence == "1")
    {
      ++rows;
      key_rows += l.keyframe;
    }
  EXPECT_EQ (ds.labels ().size (), rows);
  std::size_t key_labels = 0;
  for (const auto &l : ds.labels ())
    key_labels += l.keyframe;
  EXPECT_EQ (key_labels, key_rows);

  // Each visible tip is a surface point of the person: near a finite point of its
  // frame's portrait cloud, and it projects (dataset intrinsics) close to its
  // stored tip pixel. The pixel is the label's, mapped to the view; the 3D point
  // is the nearest foreground point within 6 full-resolution pixels (a square
  // window), so up to (6 + 0.5) * sqrt (2) * 0.4 = 3.7 portrait pixels away.
  const double max_px = (6 + 0.5) * std::sqrt (2.0) * 0.4;
  std::size_t visible = 0;
  double worst_px = 0.0, worst_m = 0.0;
  for (const auto &frame : ds.frames ())
  {
    const Cloud::Ptr cloud = ds.loadFrame (frame.id);
    ASSERT_EQ (cloud->width, 144u);
    ASSERT_EQ (cloud->height, 176u);
    for (const PartLabel &l : ds.labelsOf (frame.id))
    {
      if (!l.visible)
        continue;
      ++visible;
      const std::string what = frame.id + " " + agex::bodyPartName (l.part) + std::to_string (l.instance);
      ASSERT_TRUE (l.tip.allFinite ()) << what;
      double nearest = std::numeric_limits<double>::infinity ();
      for (const auto &p : *cloud)
        if (isFinite (p))
          nearest = std::min (nearest, static_cast<double> ((p.getVector3fMap () - l.tip).norm ()));
      EXPECT_LT (nearest, 0.05) << what << ": tip " << nearest * 100 << " cm from the frame's surface";
      const double u = info.intrinsics.fx * l.tip.x () / l.tip.z () + info.intrinsics.cx;
      const double v = info.intrinsics.fy * l.tip.y () / l.tip.z () + info.intrinsics.cy;
      const double off = std::hypot (u - l.tip_px.x (), v - l.tip_px.y ());
      EXPECT_LE (off, max_px) << what << ": tip projects to (" << u << ", " << v << "), stored pixel ("
                              << l.tip_px.x () << ", " << l.tip_px.y () << ")";
      EXPECT_GT (l.tip.z (), 1.5f) << what;
      EXPECT_LT (l.tip.z (), 3.0f) << what << ": the person stands at ~2.3 m";
      worst_px = std::max (worst_px, off);
      worst_m = std::max (worst_m, nearest);
    }
  }
  EXPECT_EQ (visible, rows) << "sequence 1 has depth near every labelled pixel";
  std::cout << "sequence 1: " << visible << " visible tips, at most " << worst_m * 100
            << " cm from the stored cloud and " << worst_px << " px from their pixel\n";
}

TEST_F (BonnConversion, ExistingOutputIsKeptWithoutForce)
{
  const std::string json = readText (fs::path (dataset ()) / "dataset.json");
  const std::string csv = readText (fs::path (dataset ()) / "labels.csv");
  EXPECT_EQ (convert ("--view full"), 1) << readText (log ());
  EXPECT_NE (readText (log ()).find ("--force"), std::string::npos) << readText (log ());
  EXPECT_EQ (readText (fs::path (dataset ()) / "dataset.json"), json);
  EXPECT_EQ (readText (fs::path (dataset ()) / "labels.csv"), csv);
  EXPECT_EQ (agex::Dataset::read (dataset ()).info ().width, 144);
  EXPECT_TRUE (stagingLeftovers (fs::path (dataset ()).parent_path ()).empty ());

  // With --force, --view full replaces it: the 640x480 frames, the Kinect intrinsics.
  ASSERT_EQ (convert ("--view full --force"), 0) << readText (log ());
  const agex::Dataset full = agex::Dataset::read (dataset ());
  EXPECT_EQ (full.info ().width, 640);
  EXPECT_EQ (full.info ().height, 480);
  EXPECT_DOUBLE_EQ (full.info ().intrinsics.fx, 525.0);
  EXPECT_DOUBLE_EQ (full.info ().intrinsics.cx, 319.5);
  ASSERT_EQ (full.frames ().size (), 33u);
  const Cloud::Ptr cloud = full.loadFrame ("1_002");
  EXPECT_EQ (cloud->width, 640u);
  EXPECT_EQ (cloud->height, 480u);
  // The same tips as in the portrait dataset (lifted on the same full frame), the
  // pixels now the labels' own.
  const agex::BonnLabel first = agex::readBonnLabels (bonn () + "/labels.csv").front ();
  const std::vector<PartLabel> labels = full.labelsOf (first.sequence + "_" + first.frame);
  ASSERT_FALSE (labels.empty ());
  EXPECT_EQ (labels.front ().tip_px, first.tip_px);
  EXPECT_TRUE (stagingLeftovers (fs::path (dataset ()).parent_path ()).empty ());

  // Bad flags fail with exit code 1 too.
  EXPECT_EQ (convert ("--force --view sideways"), 1);
  EXPECT_EQ (agex::Dataset::read (dataset ()).info ().width, 640) << "a failed run leaves the dataset alone";
}

TEST_F (BonnConversion, EvalCoverageWritesTheDocumentedReport)
{
  const std::string json_path = tmp_.file ("coverage.json");
  ASSERT_EQ (run (quoted (AGEX_EVAL_EXECUTABLE) + " coverage --dataset " + quoted (dataset ()) + " --json " +
                  quoted (json_path) + " >> " + quoted (log ()) + " 2>&1"),
             0)
      << readText (log ());
  const nlohmann::json report = nlohmann::json::parse (readText (json_path));
  EXPECT_EQ (report["frames"], 33);
  EXPECT_EQ (report["k"], 5);
  EXPECT_NEAR (report["radius_m"].get<double> (), 0.10, 1e-6);
  for (const char *part : {"head", "hand", "foot"})
  {
    SCOPED_TRACE (part);
    ASSERT_TRUE (report["coverage"][part].is_number ());
    const double c = report["coverage"][part].get<double> ();
    EXPECT_GE (c, 0.0);
    EXPECT_LE (c, 1.0);
    ASSERT_TRUE (report["orientation_median_deg"][part].is_number ());
    EXPECT_GE (report["orientation_median_deg"][part].get<double> (), 0.0);
    EXPECT_LE (report["orientation_median_deg"][part].get<double> (), 180.0);
    const nlohmann::json &curve = report["coverage_curve"][part];
    ASSERT_TRUE (curve.is_array ());
    ASSERT_EQ (curve.size (), 20u);
    for (std::size_t k = 1; k < curve.size (); ++k)
      EXPECT_GE (curve[k].get<double> (), curve[k - 1].get<double> ()) << "k = " << k + 1;
    EXPECT_DOUBLE_EQ (curve[4].get<double> (), c) << "the curve at k = 5 is the reported coverage";
  }
  // Sequence 1 is the person standing, mostly arms down: the head is among the
  // first 5 extrema in every frame (measured 1.0; 33 labels).
  EXPECT_GE (report["coverage"]["head"].get<double> (), 0.9);

  // --keyframes scores the 11 keyframes only.
  ASSERT_EQ (run (quoted (AGEX_EVAL_EXECUTABLE) + " coverage --keyframes --k 3 --dataset " + quoted (dataset ()) +
                  " --json " + quoted (json_path) + " >> " + quoted (log ()) + " 2>&1"),
             0);
  const nlohmann::json keyframes = nlohmann::json::parse (readText (json_path));
  EXPECT_EQ (keyframes["frames"], 11);
  EXPECT_EQ (keyframes["k"], 3);
  EXPECT_EQ (keyframes["labels"]["head"], 11);
  // A missing dataset fails with exit code 1.
  EXPECT_EQ (run (quoted (AGEX_EVAL_EXECUTABLE) + " coverage --dataset " + quoted (tmp_.file ("none")) + " >> " +
                  quoted (log ()) + " 2>&1"),
             1);
}
}  // namespace

// ---------------------------------------------------------------------------
// Body-part apps end to end: agex_train on Bonn sequence 1, agex_detect on a frame
// and on the dataset (JSON lines, resumable), agex_eval detect, damaged models.

namespace
{
class BodyPartApps : public BonnConversion
{
protected:
  std::string model () const { return tmp_.file ("model.yml"); }
  void SetUp () override
  {
    BonnConversion::SetUp ();
    if (IsSkipped () || HasFatalFailure ())
      return;
    // A small, fast model: enough to tell the parts apart on the frames it saw.
    ASSERT_EQ (run (quoted (AGEX_TRAIN_EXECUTABLE) + " --dataset " + quoted (dataset ()) +
                    " --weak-count 40 --fragments 20 --random-negatives 2 --out " + quoted (model ()) + " >> " +
                    quoted (log ()) + " 2>&1"),
               0)
        << readText (log ());
  }
};

std::vector<nlohmann::json>
jsonLines (const std::string &path)
{
  std::vector<nlohmann::json> lines;
  std::ifstream in (path);
  for (std::string line; std::getline (in, line);)
    lines.push_back (nlohmann::json::parse (line));
  return lines;
}
}  // namespace

TEST_F (BodyPartApps, DetectsTheHeadOfAFrameSortedByConfidence)
{
  const std::string json = tmp_.file ("detections.json"), overlay = tmp_.file ("detections.png");
  const agex::Dataset ds = agex::Dataset::read (dataset ());
  ASSERT_EQ (run (quoted (AGEX_DETECT_EXECUTABLE) + " " + quoted (ds.framePath ("1_002")) + " --model " +
                  quoted (model ()) + " --json " + quoted (json) + " --overlay " + quoted (overlay) + " >> " +
                  quoted (log ()) + " 2>&1"),
             0)
      << readText (log ());
  const auto doc = nlohmann::json::parse (readText (json));
  ASSERT_FALSE (doc.at ("detections").empty ());
  EXPECT_TRUE (fs::file_size (overlay) > 1000);
  float previous = 2.f;
  for (const auto &d : doc["detections"])
  {
    const float c = d.at ("confidence").get<float> ();
    EXPECT_LE (c, previous) << "detections must be sorted by confidence";
    EXPECT_GE (c, 0.f);
    EXPECT_LE (c, 1.f);
    previous = c;
    agex::BodyPart part;
    EXPECT_TRUE (agex::parseBodyPart (d.at ("class").get<std::string> (), part));
  }
  // The most confident head detection is the labelled head (a frame it trained on).
  Eigen::Vector3f head_tip = Eigen::Vector3f::Constant (NAN);
  for (const auto &l : ds.labelsOf ("1_002"))
    if (l.part == agex::BodyPart::Head)
      head_tip = l.tip;
  ASSERT_TRUE (head_tip.allFinite ());
  bool found = false;
  for (const auto &d : doc["detections"])
    if (d["class"] == "head")
    {
      const Eigen::Vector3f p (d["position"][0].get<float> (), d["position"][1].get<float> (),
                               d["position"][2].get<float> ());
      EXPECT_LT ((p - head_tip).norm (), 0.10f) << "most confident head detection";
      EXPECT_GT (d["confidence"].get<float> (), 0.5f);
      found = true;
      break;
    }
  EXPECT_TRUE (found) << "no head detection";
}

TEST_F (BodyPartApps, JsonLinesInParallelAndResumable)
{
  const std::string json = tmp_.file ("all.jsonl");
  const std::string command = quoted (AGEX_DETECT_EXECUTABLE) + " " + quoted (dataset ()) + " --model " +
                              quoted (model ()) + " --jobs 2 --json " + quoted (json) + " >> " + quoted (log ()) +
                              " 2>&1";
  ASSERT_EQ (run (command), 0) << readText (log ());
  auto lines = jsonLines (json);
  ASSERT_EQ (lines.size (), 33u);
  std::set<std::string> frames;
  for (const auto &l : lines)
    frames.insert (l.at ("frame").get<std::string> ());
  EXPECT_EQ (frames.size (), 33u) << "each frame once";

  // A rerun does nothing new; a torn last line (an interrupted run) is redone.
  ASSERT_EQ (run (command), 0);
  EXPECT_EQ (jsonLines (json).size (), 33u);
  std::string text = readText (json);
  text.resize (text.size () - 40);
  writeText (json, text);
  ASSERT_EQ (run (command), 0) << readText (log ());
  lines = jsonLines (json);
  EXPECT_EQ (lines.size (), 33u);
}

TEST_F (BodyPartApps, EvalDetectReportsAveragePrecision)
{
  const std::string json = tmp_.file ("eval.json");
  ASSERT_EQ (run (quoted (AGEX_EVAL_EXECUTABLE) + " detect --dataset " + quoted (dataset ()) + " --keyframes --model " +
                  quoted (model ()) + " --json " + quoted (json) + " --plots " + quoted (tmp_.file ("plots")) +
                  " >> " + quoted (log ()) + " 2>&1"),
             0)
      << readText (log ());
  const auto doc = nlohmann::json::parse (readText (json));
  EXPECT_EQ (doc.at ("frames").get<int> (), 11);
  for (const char *part : {"head", "hand", "foot"})
  {
    const double ap = doc.at ("ap").at (part).get<double> ();
    EXPECT_GE (ap, 0.0);
    EXPECT_LE (ap, 1.0);
  }
  // On frames it was trained on, the head is found.
  EXPECT_GT (doc["ap"]["head"].get<double> (), 0.5);
  EXPECT_TRUE (doc.contains ("confusion_at_0.75"));
  EXPECT_TRUE (fs::exists (tmp_.file ("plots") + "/precision_recall.png"));
}

TEST_F (BodyPartApps, BenchDatasetReportsStagesAndThroughput)
{
  const std::string json = tmp_.file ("bench.json");
  ASSERT_EQ (run (quoted (AGEX_BENCH_EXECUTABLE) + " --dataset " + quoted (dataset ()) + " --keyframes --model " +
                  quoted (model ()) + " --passes 1 --jobs 2 --json " + quoted (json) + " >> " + quoted (log ()) +
                  " 2>&1"),
             0)
      << readText (log ());
  const auto doc = nlohmann::json::parse (readText (json));
  EXPECT_EQ (doc.at ("frames").get<int> (), 11);
  const double median = doc.at ("ms_per_frame").at ("median").get<double> ();
  EXPECT_GT (median, 0.0);
  EXPECT_GE (doc["ms_per_frame"].at ("p95").get<double> (), median);
  // Every stage from the cropped frame to the classifier is timed, and none exceeds the whole.
  double stage_sum = 0;
  for (const char *stage : {"crop", "mixed_pixels", "denoise", "floor", "spurs", "segmentation", "agex", "patches",
                            "classify"})
  {
    ASSERT_TRUE (doc.at ("stages").contains (stage)) << stage;
    const double ms = doc["stages"][stage].at ("median").get<double> ();
    EXPECT_GE (ms, 0.0) << stage;
    stage_sum += ms;
  }
  EXPECT_GT (stage_sum, 0.0);
  EXPECT_EQ (doc.at ("throughput").at ("jobs").get<int> (), 2);
  EXPECT_GT (doc["throughput"].at ("frames_per_second").get<double> (), 0.0);

  // Frame files and --dataset together are refused.
  EXPECT_NE (run (quoted (AGEX_BENCH_EXECUTABLE) + " --dataset " + quoted (dataset ()) + " " +
                  quoted (AGEX_SOURCE_DIR "/data/frames/bonn_1_002.png") + " >> " + quoted (log ()) + " 2>&1"),
             0);

  // The memory run: 30 frames, sampled about every 20th of them, in the report and the JSON.
  const std::string memory_json = tmp_.file ("memory.json"), memory_out = tmp_.file ("memory.txt");
  ASSERT_EQ (run (quoted (AGEX_BENCH_EXECUTABLE) + " --dataset " + quoted (dataset ()) + " --keyframes --model " +
                  quoted (model ()) + " --passes 1 --jobs 1 --memory-frames 30 --json " + quoted (memory_json) +
                  " > " + quoted (memory_out) + " 2>&1"),
             0)
      << readText (memory_out);
  EXPECT_NE (readText (memory_out).find ("MiB after 30 frames"), std::string::npos) << readText (memory_out);
  const auto memory = nlohmann::json::parse (readText (memory_json)).at ("memory");
  EXPECT_EQ (memory.at ("frames").get<int> (), 30);
  ASSERT_EQ (memory.at ("samples").size (), 30u);  // every frame: 30 / 20 rounds down to 1
  EXPECT_EQ (memory["samples"].back ().at ("frames").get<int> (), 30);
  EXPECT_GT (memory.at ("final_bytes").get<double> (), 0.0);
  EXPECT_EQ (memory.at ("growth_bytes").get<long long> (),
             memory["final_bytes"].get<long long> () - memory.at ("after_first_pass_bytes").get<long long> ());
  // Its range, and that it needs a dataset.
  for (const std::string &bad : {" --dataset " + quoted (dataset ()) + " --memory-frames -1",
                                " --dataset " + quoted (dataset ()) + " --memory-frames 10000001",
                                " --dataset " + quoted (dataset ()) + " --keyframes --memory-frames 21",
                                std::string (" --memory-frames 10")})
  {
    const std::string out = tmp_.file ("memory_bad.txt");
    EXPECT_EQ (run (quoted (AGEX_BENCH_EXECUTABLE) + bad + " > " + quoted (out) + " 2>&1"), 1) << bad;
    EXPECT_NE (readText (out).find ("--memory-frames"), std::string::npos) << readText (out);
  }
}

TEST_F (BodyPartApps, BenchComparesTwoBuildsInTurns)
{
  // This build against itself (the build folder of agex_bench): the stages both time, a ratio
  // each; the runs' scratch reports are gone afterwards.
  const std::string json = tmp_.file ("compare.json");
  const std::string build = fs::path (AGEX_BENCH_EXECUTABLE).parent_path ().parent_path ().string ();
  const std::string scratch = tmp_.file ("scratch");
  fs::create_directories (scratch);
  ASSERT_EQ (run ("TMPDIR=" + quoted (scratch) + " " + quoted (AGEX_BENCH_EXECUTABLE) + " --dataset " + quoted (dataset () + "@1") + " --keyframes --model " +
                  quoted (model ()) + " --passes 1 --rounds 2 --compare-with " + quoted (build) + " --json " +
                  quoted (json) + " >> " + quoted (log ()) + " 2>&1"),
             0)
      << readText (log ());
  const auto doc = nlohmann::json::parse (readText (json));
  EXPECT_EQ (doc.at ("rounds").get<int> (), 2);
  for (const char *stage : {"agex", "classify", "patches"})
  {
    ASSERT_TRUE (doc.at ("stages").contains (stage)) << stage;
    EXPECT_GT (doc["stages"][stage].at ("this_ms").get<double> (), 0.0) << stage;
    EXPECT_GT (doc["stages"][stage].at ("other_ms").get<double> (), 0.0) << stage;
    EXPECT_GT (doc["stages"][stage].at ("ratio").get<double> (), 0.0) << stage;
  }
  const double total_ratio = doc.at ("total").at ("ratio").get<double> ();
  EXPECT_GT (total_ratio, 0.0);
  EXPECT_NE (readText (log ()).find ("alternating rounds"), std::string::npos);
  EXPECT_TRUE (fs::is_empty (scratch)) << "the runs' scratch folder was left behind";

  // A folder without agex_bench, and a comparison without a dataset, are refused by name.
  const std::string out = tmp_.file ("compare_errors.txt");
  EXPECT_EQ (run (quoted (AGEX_BENCH_EXECUTABLE) + " --dataset " + quoted (dataset ()) + " --compare-with " +
                  quoted (tmp_.file ("no_build")) + " > " + quoted (out) + " 2>&1"),
             1);
  EXPECT_NE (readText (out).find ("no_build: no executable bin/agex_bench"), std::string::npos) << readText (out);
  EXPECT_EQ (run (quoted (AGEX_BENCH_EXECUTABLE) + " --compare-with " + quoted (build) + " > " + quoted (out) + " 2>&1"),
             1);
  EXPECT_NE (readText (out).find ("--compare-with times the detector over a --dataset"), std::string::npos)
      << readText (out);
}

TEST_F (BodyPartApps, DamagedModelIsAClearError)
{
  const std::string damaged = tmp_.file ("damaged.yml");
  std::string text = readText (model ());
  writeText (damaged, text.substr (0, text.size () / 2));
  const std::string out = tmp_.file ("out.txt");
  EXPECT_EQ (run (quoted (AGEX_DETECT_EXECUTABLE) + " " + quoted (AGEX_SOURCE_DIR "/data/frames/bonn_1_002.png") +
                  " --model " + quoted (damaged) + " > " + quoted (out) + " 2>&1"),
             1);
  EXPECT_NE (readText (out).find (damaged), std::string::npos) << readText (out);
  EXPECT_EQ (run (quoted (AGEX_DETECT_EXECUTABLE) + " " + quoted (AGEX_SOURCE_DIR "/data/frames/bonn_1_002.png") +
                  " --model " + quoted (tmp_.file ("missing.yml")) + " > " + quoted (out) + " 2>&1"),
             1);
  EXPECT_NE (readText (out).find ("missing.yml"), std::string::npos) << readText (out);
}

TEST_F (BodyPartApps, CompareRunsBothDetectorsAndRefusesSwappedModels)
{
  const std::string sw_model = tmp_.file ("sw.yml"), json = tmp_.file ("compare.json"), out = tmp_.file ("out.txt");
  ASSERT_EQ (run (quoted (AGEX_TRAIN_EXECUTABLE) + " --sliding-window --dataset " + quoted (dataset ()) +
                  " --weak-count 40 --fragments 20 --window-negatives 10 --out " + quoted (sw_model) + " >> " +
                  quoted (log ()) + " 2>&1"),
             0)
      << readText (log ());
  ASSERT_EQ (run (quoted (AGEX_EVAL_EXECUTABLE) + " compare --dataset " + quoted (dataset ()) + " --keyframes" +
                  " --model-agex " + quoted (model ()) + " --model-sw " + quoted (sw_model) + " --json " +
                  quoted (json) + " --plots " + quoted (tmp_.file ("plots")) + " >> " + quoted (log ()) + " 2>&1"),
             0)
      << readText (log ());
  const auto doc = nlohmann::json::parse (readText (json));
  EXPECT_EQ (doc.at ("frames").get<int> (), 11);
  for (const char *side : {"agex", "sliding_window"})
    for (const char *criterion : {"iou", "distance"})
      for (const char *part : {"head", "hand", "foot"})
      {
        const double ap = doc.at (side).at ("ap").at (criterion).at (part).get<double> ();
        EXPECT_GE (ap, 0.0) << side << " " << criterion << " " << part;
        EXPECT_LE (ap, 1.0) << side << " " << criterion << " " << part;
      }
  // Both find the head of the frames they were trained on.
  EXPECT_GT (doc["agex"]["ap"]["distance"]["head"].get<double> (), 0.5);
  EXPECT_GT (doc["sliding_window"]["ap"]["distance"]["head"].get<double> (), 0.5);
  // The baseline classifies many more patches than there are AGEX points.
  EXPECT_GT (doc["sliding_window"]["patches_classified_per_frame"].get<double> (),
             5.0 * doc["agex"]["patches_classified_per_frame"].get<double> ());
  EXPECT_GT (doc["sliding_window"]["ms_per_frame"].get<double> (), 0.0);
  EXPECT_EQ (doc["agex5_containment"]["head"]["labels"].get<int> (), 11);
  EXPECT_LE (doc["agex5_containment"]["head"]["contained"].get<int> (), 11);
  for (const char *part : {"head", "hand", "foot"})
    EXPECT_TRUE (fs::exists (tmp_.file ("plots") + "/compare_" + part + ".png")) << part;

  // A model of the other kind is refused, naming the file.
  EXPECT_EQ (run (quoted (AGEX_EVAL_EXECUTABLE) + " compare --dataset " + quoted (dataset ()) + " --model-agex " +
                  quoted (model ()) + " --model-sw " + quoted (model ()) + " > " + quoted (out) + " 2>&1"),
             1);
  EXPECT_NE (readText (out).find (model () + " is an AGEX model"), std::string::npos) << readText (out);
  EXPECT_EQ (run (quoted (AGEX_DETECT_EXECUTABLE) + " " + quoted (AGEX_SOURCE_DIR "/data/frames/bonn_1_002.png") +
                  " --model " + quoted (sw_model) + " --detector-mode agex > " + quoted (out) + " 2>&1"),
             1);
  EXPECT_NE (readText (out).find (sw_model + " is a sliding-window model"), std::string::npos) << readText (out);
  // Without a mode the model's own kind runs: agex_detect runs the baseline too.
  EXPECT_EQ (run (quoted (AGEX_DETECT_EXECUTABLE) + " " + quoted (AGEX_SOURCE_DIR "/data/frames/bonn_1_002.png") +
                  " --model " + quoted (sw_model) + " --json " + quoted (tmp_.file ("sw.json")) + " 2> " + quoted (out)),
             0) << readText (out);
  EXPECT_NE (readText (tmp_.file ("sw.json")).find ("\"detector_mode\": \"sliding_window\""), std::string::npos);
}
