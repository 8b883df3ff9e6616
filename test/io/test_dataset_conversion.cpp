// Conversions into agex datasets at library level: frame files found and named, an unlabelled
// dataset written from raw .u16 frames (sequences by directory, ids by file name, one frame
// size), and the Bonn data planned and written (sequence order, inputs, the portrait view).

#include "test_support.h"

#include <agex/io/bonn.h>
#include <agex/io/dataset_conversion.h>

#include <cstdint>
#include <string>
#include <vector>

namespace
{
using namespace agex_test;

/** A raw .u16 frame of width x height pixels, every pixel depth_mm millimetres. */
void
writeU16 (const fs::path &path, int width, int height, std::uint16_t depth_mm)
{
  fs::create_directories (path.parent_path ());
  const std::vector<std::uint16_t> pixels (static_cast<std::size_t> (width) * height, depth_mm);
  writeAll (path.string (), std::string (reinterpret_cast<const char *> (pixels.data ()), pixels.size () * 2));
}

/** Reads .u16 frames of width x height pixels, the principal point at their centre. */
agex::FrameOptions
smallU16 (int width = 8, int height = 6)
{
  agex::FrameOptions options;
  options.width = width;
  options.height = height;
  options.intrinsics = {10.0, 10.0, 0.5 * width - 0.5, 0.5 * height - 0.5};
  options.intrinsics_width = options.intrinsics_height = 0;
  return options;
}

template <typename Fn> std::string
errorOf (Fn fn)
{
  try
  {
    fn ();
  }
  catch (const std::exception &e)
  {
    return e.what ();
  }
  return "";
}

TEST (FrameFilesConversion, FramesAreFoundSortedAndNamed)
{
  TempDir tmp;
  writeU16 (tmp.path () / "seq" / "b.u16", 8, 6, 1000);
  writeU16 (tmp.path () / "seq" / "a.u16", 8, 6, 1000);
  writeAll (tmp.file ("seq/notes.txt"), "not a frame");
  const std::vector<std::string> files = agex::collectFrameFiles ({tmp.file ("seq")}, ".u16");
  ASSERT_EQ (files.size (), 2u);
  EXPECT_EQ (fs::path (files[0]).filename (), "a.u16");
  EXPECT_EQ (fs::path (files[1]).filename (), "b.u16");
  EXPECT_NE (errorOf ([&] { agex::collectFrameFiles ({tmp.file ("absent")}, ".u16"); }).find ("absent: no such file"),
             std::string::npos);
  EXPECT_NE (errorOf ([&] { agex::collectFrameFiles ({tmp.file ("seq")}, ".pcd"); }).find ("no .pcd frames"),
             std::string::npos);
  EXPECT_EQ (agex::frameIdFromName ("take 1:a.b-c_d"), "take_1_a.b-c_d");
}

TEST (FrameFilesConversion, TwoDirectoriesOfOneNameAreNotMerged)
{
  TempDir tmp;
  writeU16 (tmp.path () / "train" / "seq" / "a.u16", 8, 6, 1000);
  writeU16 (tmp.path () / "test" / "seq" / "a.u16", 8, 6, 1000);
  EXPECT_NE (errorOf ([&] {
               agex::directorySequenceNames ({tmp.file ("train/seq/a.u16"), tmp.file ("test/seq/a.u16")});
             }).find ("would both be sequence 'seq'"),
             std::string::npos);
}

TEST (FrameFilesConversion, WritesAnUnlabelledDataset)
{
  TempDir tmp;
  writeU16 (tmp.path () / "one" / "x.u16", 8, 6, 1500);
  writeU16 (tmp.path () / "two" / "x.u16", 8, 6, 2000);
  const agex::FrameOptions options = smallU16 ();
  const agex::FrameFilesConversion conversion =
      agex::planFrameFilesConversion ("u16", {tmp.file ("one"), tmp.file ("two")}, "mine", "sr4000", options);
  EXPECT_EQ (conversion.files.size (), 2u);
  EXPECT_EQ (conversion.inputFiles ().size (), 4u) << "the inputs and the files";
  EXPECT_DOUBLE_EQ (conversion.info.depth_scale, 0.001) << "u16 defaults to millimetres";
  std::vector<std::size_t> steps;
  const std::size_t frames = agex::writeFrameFilesDataset (
      conversion, options, tmp.file ("out"), false, [&] (std::size_t done, std::size_t) { steps.push_back (done); });
  EXPECT_EQ (frames, 2u);
  EXPECT_EQ (steps, (std::vector<std::size_t>{1, 2}));
  const agex::Dataset dataset = agex::Dataset::read (tmp.file ("out"));
  EXPECT_EQ (dataset.info ().name, "mine");
  EXPECT_EQ (dataset.info ().sensor, "sr4000");
  EXPECT_EQ (dataset.info ().width, 8);
  EXPECT_EQ (dataset.info ().height, 6);
  ASSERT_EQ (dataset.frames ().size (), 2u);
  EXPECT_EQ (dataset.frames ()[0].id, "x");
  EXPECT_EQ (dataset.frames ()[0].sequence, "one");
  EXPECT_EQ (dataset.frames ()[1].id, "x-2") << "a repeated name is numbered";
  EXPECT_EQ (dataset.frames ()[1].sequence, "two");
  EXPECT_TRUE (dataset.labels ().empty ());
  EXPECT_NEAR (dataset.loadFrame ("x-2")->at (4, 3).z, 2.0f, 1e-6f);
}

TEST (FrameFilesConversion, OneFrameSizePerDataset)
{
  TempDir tmp;
  // Two PCD frames of different sizes, made by converting .u16 frames of those sizes.
  for (const auto &[name, side] : {std::pair<std::string, int>{"a", 8}, {"b", 4}})
  {
    writeU16 (tmp.path () / name / (name + ".u16"), side, side, 1000);
    const agex::FrameOptions options = smallU16 (side, side);
    agex::writeFrameFilesDataset (agex::planFrameFilesConversion ("u16", {tmp.file (name)}, name, "kinect", options),
                                  options, tmp.file (name + "_dataset"), false);
    fs::create_directories (tmp.path () / "mixed");
    fs::copy_file (tmp.path () / (name + "_dataset") / "frames" / (name + ".pcd"),
                   tmp.path () / "mixed" / (name + ".pcd"));
  }
  const agex::FrameFilesConversion conversion =
      agex::planFrameFilesConversion ("pcd", {tmp.file ("mixed")}, "mixed", "kinect", agex::FrameOptions ());
  EXPECT_DOUBLE_EQ (conversion.info.depth_scale, 0.0) << "PCD clouds are metres already";
  const std::string error =
      errorOf ([&] { agex::writeFrameFilesDataset (conversion, agex::FrameOptions (), tmp.file ("out"), false); });
  EXPECT_NE (error.find ("b.pcd: is 4x4, unlike the first frame (8x8); a dataset holds one frame size"),
             std::string::npos)
      << error;
  EXPECT_FALSE (fs::exists (tmp.file ("out"))) << "nothing is left of a failed conversion";
}

TEST (BonnConversionPlan, SequencesInNumericOrderAndEveryInputListed)
{
  const std::string bonn = sharedData ("bonn");
  AGEX_REQUIRE_SHARED_FILE (bonn + "/labels.csv", "the Bonn data");
  agex::BonnConversionParams params;
  params.sequences = {"2", "1"};
  const agex::BonnConversion plan = agex::planBonnConversion (bonn, params);
  ASSERT_FALSE (plan.frames.empty ());
  EXPECT_EQ (plan.params.sequences, (std::vector<std::string>{"1", "2"}));
  EXPECT_EQ (plan.frames.front ().first, "1");
  EXPECT_EQ (plan.frames.back ().first, "2");
  EXPECT_EQ (plan.inputFiles ().size (), plan.frames.size () + 2) << "the directory, labels.csv and the frames";
  EXPECT_EQ (plan.info.name, "bonn-portrait");
  EXPECT_EQ (plan.info.width, 144);
  EXPECT_EQ (plan.info.height, 176);
  EXPECT_DOUBLE_EQ (plan.info.depth_scale, 0.016);

  params.sequences = {"no-such-sequence"};
  EXPECT_NE (errorOf ([&] { agex::planBonnConversion (bonn, params); }).find ("no such sequence"), std::string::npos);
}

TEST (BonnConversionPlan, FullFramesKeepTheLabelledPixels)
{
  const std::string bonn = sharedData ("bonn");
  AGEX_REQUIRE_SHARED_FILE (bonn + "/labels.csv", "the Bonn data");
  TempDir tmp;
  agex::BonnConversionParams params;
  params.portrait = false;
  params.sequences = {"1"};
  agex::BonnConversion plan = agex::planBonnConversion (bonn, params);
  plan.frames.resize (2);  // two frames are enough
  const agex::BonnConversionStats stats = agex::writeBonnDataset (plan, tmp.file ("out"), false);
  EXPECT_EQ (stats.frames, 2u);
  const agex::Dataset dataset = agex::Dataset::read (tmp.file ("out"));
  EXPECT_EQ (dataset.info ().name, "bonn-full");
  EXPECT_EQ (dataset.info ().width, 640);
  EXPECT_EQ (dataset.labels ().size (), stats.lifted + stats.unlifted);
  std::size_t matched = 0;
  for (const auto &row : plan.labels)
    for (const auto &label : dataset.labelsOf (row.sequence + "_" + row.frame))
      if (label.part == row.part && label.instance == row.instance)
      {
        EXPECT_EQ (label.tip_px, row.tip_px) << "full frames keep the labelled pixel";
        ++matched;
      }
  EXPECT_EQ (matched, dataset.labels ().size ());
}
}  // namespace
