// Runs split over processes: --shard's parsing, the blocks every rank and shard takes (the whole
// list, in order, each frame once, sizes within one), and the merge of results parts (input
// order from the batch index, each frame once, the parts' runs checked, nothing written on a
// refusal).

#include "test_support.h"

#include <agex/apps/batch_runs.h>

#include <nlohmann/json.hpp>

#include <fstream>
#include <functional>

namespace
{
using agex_test::readAll;
using agex_test::TempDir;
using agex_test::writeAll;

TEST (Shard, ParsesKOfNAndRefusesTheRest)
{
  const agex::apps::Shard s = agex::apps::parseShard ("3/8");
  EXPECT_EQ (s.index, 3);
  EXPECT_EQ (s.count, 8);
  EXPECT_TRUE (s.given);
  for (const char *bad : {"8/8", "-1/4", "1", "1/", "/4", "a/4", "1/4/2", "1/0", "0/1000001", " 1/4", "1/4 "})
    EXPECT_THROW (agex::apps::parseShard (bad), std::runtime_error) << bad;
}

TEST (Shard, BlocksCoverTheFramesInOrderEachOnce)
{
  for (std::size_t frames = 0; frames < 40; ++frames)
    for (int n = 1; n <= 9; ++n)
    {
      std::size_t next = 0, smallest = frames, largest = 0;
      for (int k = 0; k < n; ++k)
      {
        const auto [first, last] = agex::apps::shardRange (frames, k, n);
        ASSERT_EQ (first, next) << frames << " frames, part " << k << "/" << n;
        ASSERT_LE (first, last);
        smallest = std::min (smallest, last - first);
        largest = std::max (largest, last - first);
        next = last;
      }
      EXPECT_EQ (next, frames);
      EXPECT_LE (largest - smallest, 1u) << frames << " frames in " << n;
    }
}

std::string
line (const std::string &frame, int index, int frames, const std::string &extra = "1")
{
  nlohmann::json doc = {{"frame", frame}, {"width", 64}, {"height", 48}, {"detections", nlohmann::json::array ()}, {"x", extra}};
  if (index >= 0)
    doc["batch"] = {{"index", index}, {"frames", frames}};
  return doc.dump () + "\n";
}

std::vector<std::string>
framesOf (const std::string &path)
{
  std::vector<std::string> frames;
  std::ifstream in (path);
  for (std::string l; std::getline (in, l);)
  {
    const auto doc = nlohmann::json::parse (l);
    EXPECT_FALSE (doc.contains ("batch")) << l;
    frames.push_back (doc["frame"].get<std::string> () + ":" + doc["x"].get<std::string> ());
  }
  return frames;
}

TEST (MergeResultParts, InputOrderEachFrameOnceEarlierLinesKept)
{
  TempDir dir;
  writeAll (dir.file ("p1.jsonl"), line ("d/c", 2, 4) + line ("d/d", 3, 4));
  writeAll (dir.file ("p0.jsonl"), line ("d/b", 1, 4) + line ("d/a", 0, 4));  // finish order
  // The output already holds a frame of another run, and an older copy of d/a.
  writeAll (dir.file ("out.jsonl"), line ("e/z", -1, 0) + line ("d/a", -1, 0, "old"));
  agex::apps::mergeResultParts ({dir.file ("p1.jsonl"), dir.file ("p0.jsonl")}, dir.file ("out.jsonl"), "agex_detect");
  EXPECT_EQ (framesOf (dir.file ("out.jsonl")),
             (std::vector<std::string>{"e/z:1", "d/a:1", "d/b:1", "d/c:1", "d/d:1"}));
  // The parts are inputs: untouched.
  EXPECT_EQ (readAll (dir.file ("p0.jsonl")), line ("d/b", 1, 4) + line ("d/a", 0, 4));
  // Merging again changes nothing.
  const std::string merged = readAll (dir.file ("out.jsonl"));
  agex::apps::mergeResultParts ({dir.file ("p0.jsonl"), dir.file ("p1.jsonl")}, dir.file ("out.jsonl"), "agex_detect");
  EXPECT_EQ (readAll (dir.file ("out.jsonl")), merged);
}

TEST (MergeResultParts, RefusesPartsOfOtherRunsMissingFramesAndForeignFiles)
{
  TempDir dir;
  writeAll (dir.file ("a.jsonl"), line ("d/a", 0, 3) + line ("d/b", 1, 3));
  writeAll (dir.file ("c.jsonl"), line ("d/c", 2, 3));
  writeAll (dir.file ("other_run.jsonl"), line ("d/c", 2, 5));
  writeAll (dir.file ("same_index.jsonl"), line ("d/x", 2, 3));
  writeAll (dir.file ("notes.txt"), "not results\n");
  writeAll (dir.file ("torn.jsonl"), line ("d/c", 2, 3) + "{\"frame\": \"d/");
  const std::string out = dir.file ("out.jsonl");
  auto refused = [&] (const std::vector<std::string> &parts, const std::string &needle) {
    try
    {
      agex::apps::mergeResultParts (parts, out, "agex_detect");
      ADD_FAILURE () << "merged";
    }
    catch (const std::runtime_error &e)
    {
      EXPECT_NE (std::string (e.what ()).find (needle), std::string::npos) << e.what ();
    }
    EXPECT_FALSE (std::filesystem::exists (out));
  };
  refused ({dir.file ("a.jsonl")}, "1 of 3 frames are in no part (input positions 2)");
  refused ({dir.file ("a.jsonl"), dir.file ("other_run.jsonl")}, "a run over 5 frames");
  refused ({dir.file ("a.jsonl"), dir.file ("c.jsonl"), dir.file ("same_index.jsonl")}, "both claim input position 2");
  refused ({dir.file ("a.jsonl"), dir.file ("notes.txt")}, "notes.txt: line 1 is not a frame result");
  refused ({}, "--merge needs the parts");
  refused ({dir.file ("a.jsonl"), dir.file ("missing.jsonl")}, "missing.jsonl");
  // Lines with a "frame" that are not whole results: each named by file and line.
  const auto edited = [&] (const std::string &name, const std::function<void (nlohmann::json &)> &edit) {
    nlohmann::json doc = nlohmann::json::parse (line ("d/c", 2, 3));
    edit (doc);
    writeAll (dir.file (name), doc.dump () + "\n");
    return dir.file (name);
  };
  refused ({dir.file ("a.jsonl"), edited ("empty_frame.jsonl", [] (auto &d) { d["frame"] = ""; })},
           "empty_frame.jsonl: line 1: \"frame\" is empty");
  refused ({dir.file ("a.jsonl"), edited ("none.jsonl", [] (auto &d) { d["detections"] = "none"; })},
           "none.jsonl: line 1: \"detections\" must be a list");
  refused ({dir.file ("a.jsonl"), edited ("no_detections.jsonl", [] (auto &d) { d.erase ("detections"); })},
           "no_detections.jsonl: line 1: \"detections\" must be a list");
  refused ({dir.file ("a.jsonl"), edited ("bad_entry.jsonl", [] (auto &d) { d["detections"] = {1, 2}; })},
           "bad_entry.jsonl: line 1: \"detections\" holds an entry that is not a detection");
  refused ({dir.file ("a.jsonl"), edited ("no_size.jsonl", [] (auto &d) { d["width"] = -3; })},
           "no_size.jsonl: line 1: \"width\" must be a positive whole number");
  // A torn last line (a killed shard) is skipped: the frames before it count.
  agex::apps::mergeResultParts ({dir.file ("a.jsonl"), dir.file ("torn.jsonl")}, out, "agex_detect");
  EXPECT_EQ (framesOf (out), (std::vector<std::string>{"d/a:1", "d/b:1", "d/c:1"}));
  // The output may not be one of the parts.
  EXPECT_THROW (agex::apps::mergeResultParts ({dir.file ("a.jsonl"), dir.file ("c.jsonl")}, dir.file ("c.jsonl"),
                                              "agex_detect"),
                std::runtime_error);
}
}  // namespace
