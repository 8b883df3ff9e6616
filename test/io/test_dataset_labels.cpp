// The dataset's per-pixel label images (labels/<id>.png with dataset.json's part_labels,
// persons/<id>.png) and labels.csv's optional person column: round trips, files of
// earlier versions still read, and damaged or mismatched files refused naming the file.

#include "test_support.h"

#include <agex/io/dataset.h>

#include <opencv2/imgcodecs.hpp>

#include <nlohmann/json.hpp>

#include <fstream>
#include <functional>

namespace
{
using namespace agex_test;
using agex::DatasetError;

constexpr int kWidth = 5, kHeight = 4;

agex::DatasetInfo
info ()
{
  agex::DatasetInfo i;
  i.name = "labels-test";
  i.sensor = "synthetic";
  i.width = kWidth;
  i.height = kHeight;
  i.depth_scale = 1.0;
  i.part_labels = {{1, "head"}, {9, "left_hand"}, {255, "body"}};
  return i;
}

agex::PartLabel
label (agex::BodyPart part, int instance, int person)
{
  agex::PartLabel l;
  l.part = part;
  l.instance = instance;
  l.person = person;
  l.tip = Eigen::Vector3f (0.1f, 0.2f, 2.0f);
  l.base = Eigen::Vector3f (0.1f, 0.3f, 2.0f);
  l.tip_px = Eigen::Vector2f (2.0f, 1.0f);
  l.base_px = Eigen::Vector2f (2.0f, 2.0f);
  l.keyframe = true;
  return l;
}

/** A part-label image: a head at the top row, a hand at (3, 2), body elsewhere in row 1. */
cv::Mat
parts (int variant)
{
  cv::Mat m (kHeight, kWidth, CV_8UC1, cv::Scalar (0));
  m.row (0).setTo (1);
  m.row (1).setTo (255);
  m.at<std::uint8_t> (2, 3) = static_cast<std::uint8_t> (variant ? 9 : 1);
  return m;
}

cv::Mat
persons ()
{
  cv::Mat m (kHeight, kWidth, CV_8UC1, cv::Scalar (0));
  m.rowRange (0, 2).setTo (1);
  m.at<std::uint8_t> (2, 3) = 2;
  return m;
}

/** Writes a two-frame dataset with part and person images; person 2 labelled in frame b. */
void
writeDataset (const std::string &dir)
{
  agex::DatasetWriter writer (dir, info ());
  const Cloud cloud (kWidth, kHeight, pcl::PointXYZ (0.f, 0.f, 2.f));
  writer.addFrame ("a", "s", cloud, {label (agex::BodyPart::Head, 0, 1)});
  writer.addPartLabels ("a", parts (0));
  writer.addPersonLabels ("a", persons ());
  writer.addFrame ("b", "s", cloud, {label (agex::BodyPart::Head, 0, 1), label (agex::BodyPart::Head, 0, 2),
                                     label (agex::BodyPart::Hand, 0, 2)});
  writer.addPartLabels ("b", parts (1));
  writer.addPersonLabels ("b", persons ());
  writer.commit ();
}

bool
sameImage (const cv::Mat &a, const cv::Mat &b)
{
  return a.size () == b.size () && a.type () == b.type () && cv::countNonZero (a != b) == 0;
}

/** Runs f, expecting a DatasetError whose message holds every needle. */
void
expectError (const std::function<void ()> &f, const std::vector<std::string> &needles)
{
  try
  {
    f ();
    ADD_FAILURE () << "no error; expected one naming " << needles.front ();
  }
  catch (const DatasetError &e)
  {
    for (const auto &needle : needles)
      EXPECT_NE (std::string (e.what ()).find (needle), std::string::npos) << e.what () << "\nlacks: " << needle;
  }
}

TEST (DatasetLabelImages, RoundTripPartsPersonsAndThePersonColumn)
{
  QuietPcl quiet;
  TempDir tmp;
  const std::string dir = tmp.file ("ds");
  writeDataset (dir);
  EXPECT_TRUE (fs::is_regular_file (fs::path (dir) / "labels" / "a.png"));
  EXPECT_TRUE (fs::is_regular_file (fs::path (dir) / "persons" / "b.png"));
  const auto doc = nlohmann::json::parse (readAll ((fs::path (dir) / "dataset.json").string ()));
  EXPECT_EQ (doc.at ("part_labels").at ("9"), "left_hand");
  EXPECT_EQ (doc.at ("person_labels"), true);

  const agex::Dataset ds = agex::Dataset::read (dir);
  EXPECT_EQ (ds.info ().part_labels, info ().part_labels);
  ASSERT_TRUE (ds.hasPartLabels ());
  ASSERT_TRUE (ds.hasPersonLabels ());
  EXPECT_TRUE (sameImage (ds.loadPartLabels ("a"), parts (0)));
  EXPECT_TRUE (sameImage (ds.loadPartLabels ("b"), parts (1)));
  EXPECT_TRUE (sameImage (ds.loadPersonLabels ("b"), persons ()));
  // Two people in frame b: labels.csv has the person column, and the rows keep it.
  const std::string csv = readAll ((fs::path (dir) / "labels.csv").string ());
  EXPECT_EQ (csv.substr (0, csv.find ('\n')),
             "frame,part,instance,tip_x,tip_y,tip_z,base_x,base_y,base_z,tip_u,tip_v,base_u,base_v,visible,keyframe,"
             "person");
  const auto b = ds.labelsOf ("b");
  ASSERT_EQ (b.size (), 3u);
  EXPECT_EQ (b[0].person, 1);
  EXPECT_EQ (b[1].person, 2);
  EXPECT_EQ (b[2].person, 2);
  EXPECT_EQ (b[2].part, agex::BodyPart::Hand);
}

// Single-person label files keep the layout of earlier versions, and those files (no
// person column, no label images) still read: every row is person 1.
TEST (DatasetLabelImages, FilesWithoutPersonColumnOrImagesStillRead)
{
  const std::string text = agex::formatLabelsCsv ({label (agex::BodyPart::Head, 0, 1)});
  EXPECT_EQ (text.substr (0, text.find ('\n')),
             "frame,part,instance,tip_x,tip_y,tip_z,base_x,base_y,base_z,tip_u,tip_v,base_u,base_v,visible,keyframe");
  TempDir tmp;
  const std::string dir = tmp.file ("old");
  {
    agex::DatasetInfo plain = info ();
    plain.part_labels.clear ();
    agex::DatasetWriter writer (dir, plain);
    writer.addFrame ("a", "s", Cloud (kWidth, kHeight, pcl::PointXYZ (0.f, 0.f, 2.f)),
                     {label (agex::BodyPart::Head, 0, 1), label (agex::BodyPart::Foot, 1, 1)});
    writer.commit ();
  }
  EXPECT_FALSE (fs::exists (fs::path (dir) / "labels"));
  const auto doc = nlohmann::json::parse (readAll ((fs::path (dir) / "dataset.json").string ()));
  EXPECT_FALSE (doc.contains ("part_labels"));
  EXPECT_FALSE (doc.contains ("person_labels"));
  const agex::Dataset ds = agex::Dataset::read (dir);
  EXPECT_FALSE (ds.hasPartLabels ());
  EXPECT_FALSE (ds.hasPersonLabels ());
  for (const auto &l : ds.labels ())
    EXPECT_EQ (l.person, 1);
  expectError ([&] { ds.loadPartLabels ("a"); }, {"labels/a.png", "no part_labels"});
  expectError ([&] { ds.loadPersonLabels ("a"); }, {"persons/a.png", "person_labels"});
}

TEST (DatasetLabelImages, BadPersonColumnNamesTheLine)
{
  TempDir tmp;
  const std::string header =
      "frame,part,instance,tip_x,tip_y,tip_z,base_x,base_y,base_z,tip_u,tip_v,base_u,base_v,visible,keyframe,person\n";
  const std::string row = "a,head,0,0,0,2,0,0,2,1,1,1,1,1,1,";
  auto read = [&] (const std::string &text) {
    writeAll (tmp.file ("labels.csv"), text);
    return agex::readLabelsCsv (tmp.file ("labels.csv"));
  };
  EXPECT_EQ (read (header + row + "3\n").at (0).person, 3);
  for (const std::string bad : {"0", "256", "x", "1.5", ""})
    expectError ([&] { read (header + row + bad + "\n"); }, {"labels.csv:2", "person must be an integer 1-255"});
  expectError ([&] { read (header + row + "1\n" + row + "1\n"); }, {"labels.csv:3", "duplicate", "person 1"});
  EXPECT_EQ (read (header + row + "1\n" + row + "2\n").size (), 2u) << "the same part of two people";
  // A 15-field row under the 16-column header, and a person column under the old one.
  expectError ([&] { read (header + "a,head,0,0,0,2,0,0,2,1,1,1,1,1,1\n"); }, {"labels.csv:2", "expected 16"});
  expectError ([&] { read (header.substr (0, header.size () - 8) + "\n" + row + "1\n"); },
               {"labels.csv:2", "expected 15"});
  expectError ([&] { read (header.substr (0, header.size () - 1) + ",extra\n"); }, {"labels.csv:1", "header"});
}

/** A written dataset whose files the tests below damage. */
class BadLabelImages : public ::testing::Test
{
protected:
  void SetUp () override
  {
    QuietPcl quiet;
    writeDataset (dir ());
  }
  std::string dir () const { return tmp_.file ("ds"); }
  std::string image (const std::string &folder, const std::string &id) const
  {
    return (fs::path (dir ()) / folder / (id + ".png")).string ();
  }
  void editJson (const std::function<void (nlohmann::json &)> &edit)
  {
    const std::string path = (fs::path (dir ()) / "dataset.json").string ();
    auto doc = nlohmann::json::parse (readAll (path));
    edit (doc);
    writeAll (path, doc.dump (2));
  }
  TempDir tmp_;
};

TEST_F (BadLabelImages, Control)
{
  const agex::Dataset ds = agex::Dataset::read (dir ());
  EXPECT_NO_THROW (ds.loadPartLabels ("a"));
  EXPECT_NO_THROW (ds.loadPersonLabels ("a"));
}

TEST_F (BadLabelImages, MissingImageIsRefusedOnRead)
{
  fs::remove (image ("labels", "b"));
  expectError ([&] { agex::Dataset::read (dir ()); }, {image ("labels", "b"), "missing"});
}

TEST_F (BadLabelImages, MissingPersonImageIsRefusedOnRead)
{
  fs::remove (image ("persons", "a"));
  expectError ([&] { agex::Dataset::read (dir ()); }, {image ("persons", "a"), "missing"});
}

TEST_F (BadLabelImages, TruncatedOrNotAPng)
{
  const std::string bytes = readAll (image ("labels", "a"));
  writeAll (image ("labels", "a"), bytes.substr (0, bytes.size () / 2));
  const agex::Dataset ds = agex::Dataset::read (dir ());
  expectError ([&] { ds.loadPartLabels ("a"); }, {image ("labels", "a"), "cannot decode"});
  writeAll (image ("persons", "a"), "not an image at all, but long enough");
  expectError ([&] { ds.loadPersonLabels ("a"); }, {image ("persons", "a"), "not a PNG"});
}

TEST_F (BadLabelImages, WrongSizeOrTypeOrUnlistedPart)
{
  const agex::Dataset ds = agex::Dataset::read (dir ());
  cv::imwrite (image ("labels", "a"), cv::Mat (kHeight, kWidth + 1, CV_8UC1, cv::Scalar (0)));
  expectError ([&] { ds.loadPartLabels ("a"); }, {image ("labels", "a"), "is 6x4", "5x4"});
  cv::imwrite (image ("labels", "a"), cv::Mat (kHeight, kWidth, CV_16UC1, cv::Scalar (1)));
  expectError ([&] { ds.loadPartLabels ("a"); }, {image ("labels", "a"), "16-bit", "8-bit, one channel"});
  cv::imwrite (image ("persons", "a"), cv::Mat (kHeight, kWidth, CV_8UC3, cv::Scalar (1, 1, 1)));
  expectError ([&] { ds.loadPersonLabels ("a"); }, {image ("persons", "a"), "3-channel"});
  cv::Mat unlisted = parts (0);
  unlisted.at<std::uint8_t> (3, 4) = 7;
  cv::imwrite (image ("labels", "b"), unlisted);
  expectError ([&] { ds.loadPartLabels ("b"); }, {image ("labels", "b"), "pixel (4, 3) is 7", "part_labels"});
}

TEST_F (BadLabelImages, BadPartLabelsInTheJson)
{
  const std::string json = (fs::path (dir ()) / "dataset.json").string ();
  for (const char *key : {"0", "256", "01", "head", "-1"})
  {
    editJson ([&] (nlohmann::json &doc) { doc["part_labels"] = {{key, "x"}}; });
    expectError ([&] { agex::Dataset::read (dir ()); }, {json, "part_labels", key});
  }
  editJson ([] (nlohmann::json &doc) { doc["part_labels"] = {{"3", 3}}; });
  expectError ([&] { agex::Dataset::read (dir ()); }, {json, "part_labels", "name"});
  editJson ([] (nlohmann::json &doc) { doc["part_labels"] = nlohmann::json::array ({"head"}); });
  expectError ([&] { agex::Dataset::read (dir ()); }, {json, "part_labels"});
  editJson ([] (nlohmann::json &doc) { doc["part_labels"] = {{"1", "head"}}; doc["person_labels"] = "yes"; });
  expectError ([&] { agex::Dataset::read (dir ()); }, {json, "person_labels"});
}

TEST (DatasetLabelImages, WriterRefusesMisuse)
{
  QuietPcl quiet;
  TempDir tmp;
  const Cloud cloud (kWidth, kHeight, pcl::PointXYZ (0.f, 0.f, 2.f));
  {
    agex::DatasetWriter writer (tmp.file ("a"), info ());
    writer.addFrame ("a", "s", cloud, {});
    expectError ([&] { writer.addPartLabels ("z", parts (0)); }, {"'z'", "not added"});
    expectError ([&] { writer.addPartLabels ("a", cv::Mat (kHeight, kWidth, CV_16UC1, cv::Scalar (0))); },
                 {"8-bit, one channel, 5x4"});
    expectError ([&] { writer.addPersonLabels ("a", cv::Mat (kHeight + 1, kWidth, CV_8UC1, cv::Scalar (0))); },
                 {"8-bit, one channel, 5x4"});
    cv::Mat unlisted = parts (0);
    unlisted.at<std::uint8_t> (0, 0) = 3;
    expectError ([&] { writer.addPartLabels ("a", unlisted); }, {"pixel (0, 0) is 3"});
    writer.addPartLabels ("a", parts (0));
    expectError ([&] { writer.addPartLabels ("a", parts (0)); }, {"added twice"});
    writer.addFrame ("b", "s", cloud, {});
    expectError ([&] { writer.commit (); }, {"1 of 2 frames have no part-label image"});
  }
  EXPECT_FALSE (fs::exists (tmp.file ("a"))) << "a refused commit leaves no dataset";
  {
    agex::DatasetInfo plain = info ();
    plain.part_labels.clear ();
    agex::DatasetWriter writer (tmp.file ("b"), plain);
    writer.addFrame ("a", "s", cloud, {});
    expectError ([&] { writer.addPartLabels ("a", parts (0)); }, {"names no part_labels"});
    expectError ([&] { writer.addFrame ("b", "s", cloud, {label (agex::BodyPart::Head, 0, 0)}); },
                 {"person is 0", "1-255"});
  }
  agex::DatasetInfo bad = info ();
  bad.part_labels[0] = "background";
  expectError ([&] { agex::DatasetWriter (tmp.file ("c"), bad); }, {"part label 0", "1-255"});
}
}  // namespace
