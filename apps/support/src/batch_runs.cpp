#include <agex/apps/batch_runs.h>

#include <agex/apps/output_guard.h>
#include <agex/apps/results_file.h>
#include <agex/io/atomic_file.h>
#include <agex/io/input_file.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

namespace fs = std::filesystem;

namespace agex
{
namespace apps
{
namespace
{
constexpr int kMaxShards = 100000;
constexpr int kMaxLineDepth = 64;  // our lines nest 4 levels; bound what a foreign file may make us build

/** One frame result read back from a results file. */
struct ResultLine
{
  std::string frame;
  long long index = -1;    ///< its frame's position among all the inputs' frames; -1: unknown
  long long frames = -1;   ///< how many frames that run had; -1: unknown
  nlohmann::json doc;
};

/** What makes a line with a "frame" no whole frame result of agex_detect (what a merge would
  * pass on as real: a frame without a name, detections that are not a list of detections);
  * "" for a whole one. */
std::string
resultLineProblem (const nlohmann::json &doc)
{
  if (doc["frame"].get<std::string> ().empty ())
    return "\"frame\" is empty";
  for (const char *key : {"width", "height"})
    if (!doc.contains (key) || !doc[key].is_number_unsigned () || doc[key].get<unsigned long long> () == 0)
      return std::string ("\"") + key + "\" must be a positive whole number";
  if (!doc.contains ("detections") || !doc["detections"].is_array ())
    return "\"detections\" must be a list";
  for (const auto &d : doc["detections"])
    if (!d.is_object () || !d.contains ("class") || !d["class"].is_string () || !d.contains ("confidence") ||
        !d["confidence"].is_number () || !d.contains ("pixel") || !d["pixel"].is_array ())
      return "\"detections\" holds an entry that is not a detection (class, confidence, pixel)";
  if (doc.contains ("persons") && !doc["persons"].is_array ())
    return "\"persons\" must be a list";
  return "";
}

/** The frame results of a JSON-lines results file. A torn last line (an interrupted run) is
  * skipped with a warning; any other line that is not a frame result is refused. */
std::vector<ResultLine>
readResultLines (const std::string &path, const std::string &app)
{
  std::ifstream in (path, std::ios::binary);
  if (!in)
    throw std::runtime_error (path + ": cannot be read");
  std::vector<ResultLine> lines;
  std::string line;
  std::size_t number = 0;
  while (std::getline (in, line))
  {
    ++number;
    if (line.empty ())
      continue;
    const bool last = in.peek () == std::char_traits<char>::eof ();
    nlohmann::json doc = nlohmann::json::parse (
        line, [] (int depth, nlohmann::json::parse_event_t, nlohmann::json &) { return depth <= kMaxLineDepth; }, false);
    if (!doc.is_object () || !doc.contains ("frame") || !doc["frame"].is_string ())
    {
      if (last && line[0] == '{' && doc.is_discarded ())
      {
        std::cerr << app << ": " << path << ": line " << number << " is torn (an interrupted run); skipped\n";
        break;
      }
      throw std::runtime_error (path + ": line " + std::to_string (number) + " is not a frame result of " + app +
                                " (a JSON object with a \"frame\"); only results files can be merged");
    }
    const std::string wrong = resultLineProblem (doc);
    if (!wrong.empty ())
      throw std::runtime_error (path + ": line " + std::to_string (number) + ": " + wrong +
                                "; a frame result of " + app + " is not merged unless it is whole");
    ResultLine result;
    result.frame = doc["frame"].get<std::string> ();
    if (doc.contains ("batch"))
    {
      const auto &batch = doc["batch"];
      if (!batch.is_object () || !batch.contains ("index") || !batch.contains ("frames") ||
          !batch["index"].is_number_unsigned () || !batch["frames"].is_number_unsigned () ||
          batch["index"].get<unsigned long long> () >= batch["frames"].get<unsigned long long> () ||
          batch["frames"].get<unsigned long long> () > (1ull << 40))
        throw std::runtime_error (path + ": line " + std::to_string (number) +
                                  ": \"batch\" must be {\"index\": i, \"frames\": n} with 0 <= i < n");
      result.index = static_cast<long long> (batch["index"].get<unsigned long long> ());
      result.frames = static_cast<long long> (batch["frames"].get<unsigned long long> ());
    }
    result.doc = std::move (doc);
    lines.push_back (std::move (result));
  }
  return lines;
}

/** The parts an MPI run over out writes and leaves: "<out>.part-R-of-N", any N. */
std::vector<std::string>
mpiParts (const std::string &out)
{
  const fs::path path (out);
  const fs::path dir = path.parent_path ().empty () ? fs::path (".") : path.parent_path ();
  const std::string base = path.filename ().string ();
  std::vector<std::string> parts;
  std::error_code ec;
  for (const auto &entry : fs::directory_iterator (dir, ec))
  {
    const std::string name = entry.path ().filename ().string ();
    if (name.size () <= base.size () || name.compare (0, base.size (), base) != 0)
      continue;
    static const std::regex pattern (R"(\.part-[0-9]{1,6}-of-[0-9]{1,6})");
    if (std::regex_match (name.substr (base.size ()), pattern) && entry.is_regular_file (ec))
      parts.push_back ((path.parent_path () / name).string ());
  }
  std::sort (parts.begin (), parts.end ());
  return parts;
}

/** A digest of the frames' names in order (FNV-1a), for the ranks to check they list the same. */
std::string
framesDigest (const std::vector<FrameJob> &jobs)
{
  std::uint64_t h = 1469598103934665603ull;
  for (const auto &job : jobs)
    for (const char c : job.name + '\n')
      h = (h ^ static_cast<unsigned char> (c)) * 1099511628211ull;
  char text[17];
  std::snprintf (text, sizeof text, "%016llx", static_cast<unsigned long long> (h));
  return text;
}

std::string
mpiPart (const std::string &out, int rank, int size)
{
  return out + ".part-" + std::to_string (rank) + "-of-" + std::to_string (size);
}

/** Joins out's earlier frames and the parts' into out (see mergeResultParts). */
void
mergeInto (const std::vector<std::string> &parts, const std::string &out, const std::string &app,
           const std::vector<FrameJob> *order)
{
  std::vector<ResultLine> lines;
  std::error_code ec;
  if (fs::exists (out, ec) && fs::file_size (out, ec) > 0)
    lines = readResultLines (out, app);
  std::vector<std::pair<std::string, long long>> frame_counts;  // (file, frames) of each indexed file
  for (const auto &part : parts)
  {
    std::vector<ResultLine> more = readResultLines (part, app);
    for (const auto &l : more)
      if (l.frames >= 0 && (frame_counts.empty () || frame_counts.back ().first != part))
        frame_counts.emplace_back (part, l.frames);
      else if (l.frames >= 0 && l.frames != frame_counts.back ().second)
        throw std::runtime_error (part + ": its lines come from runs over " + std::to_string (l.frames) + " and " +
                                  std::to_string (frame_counts.back ().second) + " frames");
    std::move (more.begin (), more.end (), std::back_inserter (lines));
  }
  long long total = -1;
  for (const auto &[file, frames] : frame_counts)
    if (total < 0)
      total = frames;
    else if (frames != total)
      throw std::runtime_error (file + ": a part of a run over " + std::to_string (frames) + " frames, but " +
                                frame_counts.front ().first + " is of a run over " + std::to_string (total) +
                                " frames; merge the parts of one run");
  if (order)
  {
    std::unordered_map<std::string, long long> position;
    for (std::size_t i = 0; i < order->size (); ++i)
      position.emplace ((*order)[i].name, static_cast<long long> (i));
    for (auto &l : lines)
    {
      const auto it = position.find (l.frame);
      l.index = it == position.end () ? -1 : it->second;
    }
    total = static_cast<long long> (order->size ());
  }
  // Each frame once: an indexed line before an unindexed one, else the first.
  std::vector<const ResultLine *> chosen;
  std::unordered_map<std::string, std::size_t> slot_of;
  for (const auto &l : lines)
  {
    const auto [it, inserted] = slot_of.emplace (l.frame, chosen.size ());
    if (inserted)
      chosen.push_back (&l);
    else if (chosen[it->second]->index < 0 && l.index >= 0)
      chosen[it->second] = &l;
  }
  std::map<long long, const ResultLine *> by_index;
  std::vector<const ResultLine *> unindexed;
  for (const ResultLine *l : chosen)
  {
    if (l->index < 0)
    {
      unindexed.push_back (l);
      continue;
    }
    const auto [it, inserted] = by_index.emplace (l->index, l);
    if (!inserted)
      throw std::runtime_error ("frames " + it->second->frame + " and " + l->frame + " both claim input position " +
                                std::to_string (l->index) + "; the parts come from different runs");
  }
  if (total >= 0 && static_cast<long long> (by_index.size ()) < total)
  {
    std::ostringstream missing;
    int named = 0;
    for (long long i = 0; i < total && named < 5; ++i)
      if (!by_index.count (i))
        missing << (named++ ? ", " : "") << i;
    throw std::runtime_error (out + ": " + std::to_string (total - static_cast<long long> (by_index.size ())) + " of " +
                              std::to_string (total) + " frames are in no part (input positions " + missing.str () +
                              (total - static_cast<long long> (by_index.size ()) > 5 ? ", ..." : "") +
                              "): a shard did not finish; rerun it, then merge again");
  }
  std::string bytes;
  auto add = [&] (const ResultLine &l) {
    nlohmann::json doc = l.doc;
    doc.erase ("batch");
    bytes += doc.dump () + "\n";
  };
  for (const ResultLine *l : unindexed)
    add (*l);
  for (const auto &[index, l] : by_index)
    add (*l);
  writeFileAtomic (out, bytes);
}
}  // namespace

Shard
parseShard (const std::string &text)
{
  Shard shard;
  const auto slash = text.find ('/');
  auto number = [&] (const std::string &digits, int &value) {
    if (digits.empty () || digits.size () > 6 || !std::all_of (digits.begin (), digits.end (), [] (unsigned char c) { return c >= '0' && c <= '9'; }))
      return false;
    value = std::stoi (digits);
    return true;
  };
  if (slash == std::string::npos || !number (text.substr (0, slash), shard.index) ||
      !number (text.substr (slash + 1), shard.count) || shard.count < 1 || shard.count > kMaxShards ||
      shard.index >= shard.count)
    throw std::runtime_error ("--shard takes K/N, the K-th of N parts with 0 <= K < N <= " +
                              std::to_string (kMaxShards) + " (e.g. --shard $SLURM_ARRAY_TASK_ID/4), not '" + text + "'");
  shard.given = true;
  return shard;
}

std::pair<std::size_t, std::size_t>
shardRange (std::size_t frames, int k, int n)
{
  const auto at = [&] (int part) {
    return static_cast<std::size_t> (static_cast<unsigned long long> (frames) * static_cast<unsigned long long> (part) /
                                     static_cast<unsigned long long> (n));
  };
  return {at (k), at (k + 1)};
}

void
mergeResultParts (const std::vector<std::string> &parts, const std::string &out, const std::string &app,
                  const std::vector<FrameJob> *order)
{
  if (parts.empty ())
    throw std::runtime_error ("--merge needs the parts to join (the --json files of the --shard runs)");
  if (out.empty ())
    throw std::runtime_error ("--merge needs --json OUT, the file to write the joined results to");
  InputFiles read;
  for (const auto &part : parts)
  {
    const std::string problem = notARegularFile (part);
    if (!problem.empty ())
      throw std::runtime_error (part + ": " + problem + "; --merge takes results files");
    read.add (part);
  }
  checkOutputPath (out, OutputKind::JsonLines, read);
  mergeInto (parts, out, app, order);
}

void
runDetectionBatch (const std::vector<FrameJob> &jobs, const std::string &json_path, int threads, const Shard &shard,
                   ProcessGroup &group, const std::string &app,
                   const std::function<nlohmann::json (const FrameJob &)> &process)
{
  std::unordered_map<std::string, std::size_t> index_of;
  for (std::size_t i = 0; i < jobs.size (); ++i)
    index_of.emplace (jobs[i].name, i);
  // Lines of a part carry their frame's input position, for the merge.
  const auto indexed = [&] (const FrameJob &job) {
    nlohmann::json doc = process (job);
    doc["batch"] = {{"index", index_of.at (job.name)}, {"frames", jobs.size ()}};
    return doc;
  };

  if (!group.distributed ())
  {
    std::unique_ptr<ResultsFile> results;
    if (!json_path.empty ())
      results = std::make_unique<ResultsFile> (json_path, app);
    if (!shard.given)
    {
      runFrameBatch (jobs, results.get (), threads, process);
      return;
    }
    const auto [first, last] = shardRange (jobs.size (), shard.index, shard.count);
    if (first == last)
      std::cerr << app << ": shard " << shard.index << "/" << shard.count << " has no frames (the inputs hold "
                << jobs.size () << ")\n";
    const std::vector<FrameJob> mine (jobs.begin () + static_cast<std::ptrdiff_t> (first),
                                      jobs.begin () + static_cast<std::ptrdiff_t> (last));
    runFrameBatch (mine, results.get (), threads, indexed);
    return;
  }

  if (json_path.empty ())
    throw std::runtime_error ("under mpirun, --json is required: each rank writes its part beside it, and rank 0 "
                              "merges them into it");
  if (shard.given)
    throw std::runtime_error ("--shard and mpirun both split the frames; use one of them");
  const int rank = group.rank (), size = group.size ();

  // 1. Rank 0 locks the output and says which frames are done: in it, or in the parts any
  //    earlier run over it left.
  std::unique_ptr<ResultsFile> out;
  std::string status;
  if (rank == 0)
  {
    try
    {
      out = std::make_unique<ResultsFile> (json_path, app);
      std::set<std::string> in_parts;
      for (const auto &part : mpiParts (json_path))
        for (const auto &line : readResultLines (part, app))
          in_parts.insert (line.frame);
      status = "1" + framesDigest (jobs);
      for (const auto &job : jobs)
        status += out->contains (job.name) || in_parts.count (job.name) ? '1' : '0';
    }
    catch (const std::exception &e)
    {
      status = std::string ("0") + e.what ();
    }
  }
  status = group.broadcast (status);
  if (status[0] != '1')
  {
    if (rank == 0)
      throw std::runtime_error (status.substr (1));
    return;  // rank 0 says why; its exit status fails the run
  }

  // 2. Every rank does the frames of its share into its own part.
  const auto [first, last] = shardRange (jobs.size (), rank, size);
  constexpr std::size_t kMask = 1 + 16;  // where the done flags start, after "1" and the digest
  std::string error;
  try
  {
    if (status.compare (1, 16, framesDigest (jobs)) != 0 || status.size () != kMask + jobs.size ())
      throw std::runtime_error ("this rank lists other frames than rank 0 (" + std::to_string (jobs.size ()) +
                                " here, " + std::to_string (status.size () - std::min (status.size (), kMask)) +
                                " there): the inputs must be the same files for every rank, on a file system "
                                "they all see");
    std::vector<FrameJob> todo;
    for (std::size_t i = first; i < last; ++i)
      if (status[kMask + i] == '0')
        todo.push_back (jobs[i]);
    ResultsFile part (mpiPart (json_path, rank, size), app);
    runFrameBatch (todo, &part, threads, indexed);
  }
  catch (const std::exception &e)
  {
    error = e.what ();
  }

  // 3. Rank 0 hears from every rank, and merges when all are done.
  const std::vector<std::string> errors = group.gather (error);
  std::string verdict = "1";
  if (rank == 0)
  {
    std::string failed;
    for (int r = 1; r < size; ++r)
      if (!errors[r].empty ())
        failed += (failed.empty () ? "" : ", ") + std::to_string (r);
    if (!failed.empty ())
      verdict = "0rank(s) " + failed + " failed (see their messages); nothing merged into " + json_path +
                ": the frames done are kept in its parts (" + json_path +
                ".part-*); rerun the same command to go on";
    else if (error.empty ())
    {
      try
      {
        const std::vector<std::string> parts = mpiParts (json_path);
        mergeInto (parts, json_path, app, &jobs);
        for (const auto &part : parts)
          fs::remove (part);
      }
      catch (const std::exception &e)
      {
        verdict = std::string ("0") + e.what ();
      }
    }
  }
  if (!error.empty ())
    throw std::runtime_error ("rank " + std::to_string (rank) + ": " + error);
  if (rank == 0 && verdict[0] != '1')
    throw std::runtime_error (verdict.substr (1));
}
}  // namespace apps
}  // namespace agex
