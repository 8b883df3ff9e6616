// PCL's people forests (gpu/people, Buys et al. 2014) in PCL's text format, plain or
// bzip2-compressed: trees.cpp loadTree, read strictly (one item per line, every value in
// range) so that a malformed or truncated file is refused naming its file and line.

#include <agex/classification/body_part_forest.h>
#include <agex/classification/body_part_label_point.h>

#include <boost/iostreams/filter/bzip2.hpp>
#include <boost/iostreams/filtering_stream.hpp>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <istream>
#include <string_view>

namespace agex
{
namespace
{
/** Mean bytes a line of a tree file may take (36 for PCL's longest). */
constexpr std::uint64_t kMaxMeanLineBytes = 64;

/** What the trees of one forest may still load, shared by its files. */
struct ForestBudget
{
  std::uint64_t nodes = BodyPartForest::kMaxForestNodes;
  std::uint64_t text_bytes = BodyPartForest::kMaxForestTextBytes;
};

/** Lines of a stream, read in large blocks (std::getline on a decompressing stream is slow),
  * never more than a limit of bytes: lines are bounded, but padded ones compress well. */
class LineReader
{
public:
  LineReader (std::istream &in, const std::string &name, std::uint64_t limit, std::size_t block = kBlock)
    : in_ (in), name_ (name), limit_ (limit), buffer_ (block)
  {}

  /** The next line without its "\n" or "\r\n"; false at the end. last_had_newline () says
    * whether the line returned last ended with a newline. */
  bool next (std::string_view &line)
  {
    for (;;)
    {
      const char *begin = buffer_.data () + pos_;
      const char *nl = static_cast<const char *> (std::memchr (begin, '\n', end_ - pos_));
      if (nl)
      {
        line = std::string_view (begin, static_cast<std::size_t> (nl - begin));
        pos_ += line.size () + 1;
        newline_ = true;
        break;
      }
      if (eof_)
      {
        if (pos_ == end_)
          return false;
        line = std::string_view (begin, end_ - pos_);
        pos_ = end_;
        newline_ = false;
        break;
      }
      // Keep the partial line, read the next block behind it.
      const std::size_t rest = end_ - pos_;
      if (rest >= kMaxLine)
        throw ModelError (name_ + ":" + std::to_string (line_ + 1) + ": a line longer than " +
                          std::to_string (kMaxLine) + " bytes");
      std::memmove (buffer_.data (), begin, rest);
      pos_ = 0;
      end_ = rest;
      in_.read (buffer_.data () + end_, static_cast<std::streamsize> (buffer_.size () - end_));
      const auto got = static_cast<std::size_t> (in_.gcount ());
      read_ += got;
      if (read_ > limit_)
        throw ModelError (name_ + ":" + std::to_string (line_ + 1) + ": more than " + std::to_string (limit_) +
                          " bytes of text " + limit_reason_);
      end_ += got;
      if (!in_)
      {
        if (in_.bad ())
          throw ModelError (name_ + ":" + std::to_string (line_ + 1) + ": read error");
        eof_ = true;
      }
    }
    ++line_;
    if (!line.empty () && line.back () == '\r')
      line.remove_suffix (1);
    return true;
  }
  /** Lowers the limit (the reason completes "more than N bytes of text ..."). */
  void limit (std::uint64_t bytes, const std::string &reason)
  {
    if (bytes < limit_)
    {
      limit_ = bytes;
      limit_reason_ = reason;
    }
  }
  std::uint64_t bytesRead () const { return read_; }
  std::size_t lineNumber () const { return line_; }
  bool lastHadNewline () const { return newline_; }

private:
  static constexpr std::size_t kBlock = std::size_t (1) << 20;
  static constexpr std::size_t kMaxLine = 4096;
  std::istream &in_;
  const std::string &name_;
  std::uint64_t limit_, read_ = 0;
  std::string limit_reason_ = "in this forest's tree files (kMaxForestTextBytes)";
  std::vector<char> buffer_;
  std::size_t pos_ = 0, end_ = 0, line_ = 0;
  bool eof_ = false, newline_ = true;
};

/** Whitespace-separated integers of a line; false if a token is not a decimal integer in
  * [lo, hi] or there are not exactly n of them. */
bool
parseIntegers (std::string_view line, int n, long lo, long hi, long *out)
{
  std::size_t i = 0;
  int count = 0;
  auto space = [] (char c) { return c == ' ' || c == '\t'; };
  for (;;)
  {
    while (i < line.size () && space (line[i]))
      ++i;
    if (i == line.size ())
      break;
    if (count == n)
      return false;
    bool negative = false;
    if (line[i] == '+' || line[i] == '-')
      negative = line[i++] == '-';
    const std::size_t start = i;
    long value = 0;
    while (i < line.size () && line[i] >= '0' && line[i] <= '9')
    {
      value = value * 10 + (line[i] - '0');
      if (value > 1000000)
        return false;
      ++i;
    }
    if (i == start || (i < line.size () && !space (line[i])))
      return false;
    value = negative ? -value : value;
    if (value < lo || value > hi)
      return false;
    out[count++] = value;
  }
  return count == n;
}

bool
blank (std::string_view line)
{
  return std::all_of (line.begin (), line.end (), [] (char c) { return c == ' ' || c == '\t'; });
}

/** A tree file's text, decompressed as it is read when the file is bzip2 (by content). */
class TreeText
{
public:
  explicit TreeText (const std::string &path)
  {
    std::error_code ec;
    if (!std::filesystem::is_regular_file (path, ec))
      throw ModelError (path + ": no such file");
    file_.open (path, std::ios::binary);
    if (!file_)
      throw ModelError (path + ": cannot open");
    char head[3] = {};
    file_.read (head, 3);
    bz2_ = file_.gcount () == 3 && head[0] == 'B' && head[1] == 'Z' && head[2] == 'h';
    file_.clear ();
    file_.seekg (0);
    if (bz2_)
    {
      z_.push (boost::iostreams::bzip2_decompressor ());
      z_.push (file_);
      // Decompression errors reach us as exceptions, not as a silently short stream.
      z_.exceptions (std::ios::badbit);
    }
  }
  bool compressed () const { return bz2_; }
  std::istream &stream () { return bz2_ ? static_cast<std::istream &> (z_) : file_; }

private:
  std::ifstream file_;
  boost::iostreams::filtering_istream z_;
  bool bz2_ = false;
};

/** Runs fn on the file's text; bzip2 errors become ModelErrors naming the file. */
template <typename Fn>
auto
withTreeText (const std::string &path, Fn fn)
{
  TreeText text (path);
  try
  {
    return fn (text);
  }
  catch (const ModelError &)
  {
    throw;
  }
  catch (const std::exception &e)
  {
    throw ModelError (path + ": damaged bzip2 data (" + e.what () + ")");
  }
}

/** The depth a tree file declares on its first line; 0 if it does not (reading it says why). */
int
declaredDepth (const std::string &path)
{
  return withTreeText (path, [&] (TreeText &text) {
    LineReader lines (text.stream (), path, 4096, 4096);
    std::string_view line;
    long depth = 0;
    return lines.next (line) && parseIntegers (line, 1, 1, BodyPartForest::kMaxDepth, &depth) ? static_cast<int> (depth)
                                                                                               : 0;
  });
}

BodyPartForest::Tree
readPclTreeBounded (std::istream &text, const std::string &name, ForestBudget &budget);

BodyPartForest::Tree
readTreeFile (const std::string &path, ForestBudget &budget)
{
  return withTreeText (path, [&] (TreeText &text) {
    if (!text.compressed ())
    {
      // A plain file must at least hold every line of the depth it declares: checked against
      // its size before anything of that size is allocated.
      const int depth = declaredDepth (path);
      std::error_code ec;
      const std::uintmax_t size = std::filesystem::file_size (path, ec);
      if (depth > 0 && !ec)
      {
        const std::uintmax_t nodes = (std::uintmax_t (1) << depth) - 1, leaves = std::uintmax_t (1) << depth;
        const std::uintmax_t minimum = 2 + nodes * 10 + leaves * 2;
        if (size < minimum)
          throw ModelError (path + ": truncated: " + std::to_string (size) + " bytes, a depth-" +
                            std::to_string (depth) + " tree needs at least " + std::to_string (minimum));
      }
    }
    return readPclTreeBounded (text.stream (), path, budget);
  });
}
}  // namespace

BodyPartForest::Tree
BodyPartForest::readPclTree (std::istream &text, const std::string &name)
{
  ForestBudget budget;
  return readPclTreeBounded (text, name, budget);
}

namespace
{
BodyPartForest::Tree
readPclTreeBounded (std::istream &text, const std::string &name, ForestBudget &budget)
{
  using Tree = BodyPartForest::Tree;
  using Node = BodyPartForest::Node;
  constexpr int kMaxDepth = BodyPartForest::kMaxDepth, kPclLabelCount = BodyPartForest::kPclLabelCount;
  LineReader lines (text, name, budget.text_bytes);
  // Past the tree's lines only blank ones are allowed, up to this many.
  constexpr std::size_t kMaxTrailingLines = 1024;
  std::string_view line;
  auto where = [&] () { return name + ":" + std::to_string (lines.lineNumber ()) + ": "; };
  auto truncated = [&] (const std::string &what) {
    return ModelError (name + ": truncated after line " + std::to_string (lines.lineNumber ()) + ": " + what);
  };
  long value[5];
  if (!lines.next (line))
    throw ModelError (name + ":1: empty, not a PCL tree file");
  if (!parseIntegers (line, 1, 0, 1000000, value))
    throw ModelError (where () + "expected the tree depth (one integer)");
  if (value[0] < 1 || value[0] > kMaxDepth)
    throw ModelError (where () + "tree depth " + std::to_string (value[0]) + " out of range [1, " +
                      std::to_string (kMaxDepth) + "]");
  Tree tree;
  tree.complete = true;
  tree.depth = static_cast<int> (value[0]);
  const std::size_t nodes = (std::size_t (1) << tree.depth) - 1, leaves = nodes + 1;
  if (nodes > budget.nodes)
    throw ModelError (where () + "a depth-" + std::to_string (tree.depth) + " tree (" + std::to_string (nodes) +
                      " nodes) takes the forest past " + std::to_string (BodyPartForest::kMaxForestNodes) +
                      " nodes (kMaxForestNodes)");
  budget.nodes -= nodes;
  // PCL's longest line, "-32768 -32768 -32768 -32768 -32768\r\n", has 36 bytes.
  lines.limit ((nodes + leaves + 1 + kMaxTrailingLines) * kMaxMeanLineBytes,
               "for a depth-" + std::to_string (tree.depth) + " tree (" + std::to_string (kMaxMeanLineBytes) +
                 " bytes a line on average)");
  // Grown as lines arrive: a short file cannot make us allocate what it claims.
  tree.nodes.reserve (std::min<std::size_t> (nodes, 1 << 16));
  tree.leaf_labels.reserve (std::min<std::size_t> (leaves, 1 << 16));
  for (std::size_t i = 0; i < nodes; ++i)
  {
    if (!lines.next (line))
      throw truncated ("node " + std::to_string (i + 1) + " of " + std::to_string (nodes) + " missing");
    // trees.h: du1 dv1 du2 dv2 (AttribLocation, int16) and thresh (Attrib, int16).
    if (!parseIntegers (line, 5, -32768, 32767, value))
      throw ModelError (where () + "expected a node: five integers du1 dv1 du2 dv2 threshold in [-32768, 32767]");
    Node n;
    n.du1 = static_cast<std::int16_t> (value[0]);
    n.dv1 = static_cast<std::int16_t> (value[1]);
    n.du2 = static_cast<std::int16_t> (value[2]);
    n.dv2 = static_cast<std::int16_t> (value[3]);
    n.threshold = static_cast<float> (value[4]);  // exact: delta > (int) thresh == float compare
    tree.nodes.push_back (n);
  }
  for (std::size_t i = 0; i < leaves; ++i)
  {
    if (!lines.next (line))
      throw truncated ("leaf " + std::to_string (i + 1) + " of " + std::to_string (leaves) + " missing");
    if (!parseIntegers (line, 1, 0, kPclLabelCount - 1, value))
      throw ModelError (where () + "expected a leaf: one label in [0, " + std::to_string (kPclLabelCount - 1) + "]");
    tree.leaf_labels.push_back (static_cast<std::uint8_t> (value[0]));
  }
  if (!lines.lastHadNewline ())
    throw truncated ("the last line has no newline");
  for (int extra = 0; lines.next (line); ++extra)
    if (!blank (line) || extra > static_cast<int> (kMaxTrailingLines))
      throw ModelError (where () + "unexpected content after the last leaf");
  budget.text_bytes -= lines.bytesRead ();
  return tree;
}
}  // namespace

std::vector<BodyPartForest::ClassInfo>
BodyPartForest::pclClasses ()
{
  // label_common.h, enum part_t.
  static const char *names[kPclLabelCount] = {
    "Lfoot",  "Lleg",   "Lknee",  "Lthigh", "Rfoot",     "Rleg",      "Rknee",       "Rthigh",
    "Rhips",  "Lhips",  "Neck",   "Rarm",   "Relbow",    "Rforearm",  "Rhand",       "Larm",
    "Lelbow", "Lforearm", "Lhand", "FaceLB", "FaceRB",   "FaceLT",    "FaceRT",      "Rchest",
    "Lchest", "Lshoulder", "Rshoulder", "Groundplane", "Ceiling", "Background", "Plane", "NOLABEL"};
  std::vector<ClassInfo> classes (kPclLabelCount);
  for (int i = 0; i < kPclLabelCount; ++i)
  {
    classes[i].name = names[i];
    if (i >= 19 && i <= 22)
      classes[i].part = kLabelHead;
    else if (i == 14 || i == 18)
      classes[i].part = kLabelHand;
    else if (i == 0 || i == 4)
      classes[i].part = kLabelFoot;
    else if (i <= 26)
      classes[i].part = kLabelOtherBody;
    else
      classes[i].part = kLabelNone;
  }
  return classes;
}

std::vector<std::string>
BodyPartForest::findPclTreeFiles (const std::string &directory)
{
  namespace fs = std::filesystem;
  std::vector<std::string> files;
  auto endsWith = [] (const std::string &s, const char *suffix) {
    const std::size_t n = std::strlen (suffix);
    return s.size () >= n && s.compare (s.size () - n, n, suffix) == 0;
  };
  try
  {
    // Bounded: each level holds an open directory and its path, and a symlink may loop.
    std::size_t entries = 0;
    for (auto it = fs::recursive_directory_iterator (directory, fs::directory_options::follow_directory_symlink);
         it != fs::recursive_directory_iterator (); ++it)
    {
      const fs::directory_entry &entry = *it;
      if (++entries > kMaxSearchEntries)
        throw ModelError (directory + ": more than " + std::to_string (kMaxSearchEntries) +
                          " entries below it; give the forest's own directory");
      if (it.depth () >= kMaxSearchDepth && entry.is_directory ())
        throw ModelError (directory + ": folders nested deeper than " + std::to_string (kMaxSearchDepth) +
                          " levels below it (" + entry.path ().string ().substr (0, 200) +
                          "...); give the forest's own directory");
      const std::string name = entry.path ().filename ().string ();
      if (entry.is_regular_file () && (endsWith (name, ".txt") || endsWith (name, ".txt.bz2")))
        files.push_back (entry.path ().string ());
    }
  }
  catch (const fs::filesystem_error &e)
  {
    throw ModelError (directory + ": cannot list (" + e.code ().message () + ")");
  }
  if (files.empty ())
    throw ModelError (directory + ": no PCL tree files (*.txt, *.txt.bz2) found");
  std::sort (files.begin (), files.end ());
  if (files.size () > static_cast<std::size_t> (kMaxTrees))
    throw ModelError (directory + ": " + std::to_string (files.size ()) + " tree files, at most " +
                      std::to_string (kMaxTrees) + " trees per forest");
  return files;
}

BodyPartForest::Ptr
BodyPartForest::loadPclTrees (const std::vector<std::string> &files)
{
  if (files.empty ())
    throw ModelError ("no PCL tree files given");
  if (files.size () > static_cast<std::size_t> (kMaxTrees))
    throw ModelError (std::to_string (files.size ()) + " tree files, at most " + std::to_string (kMaxTrees) + " trees");
  // The declared depths first: a forest too large is refused before any tree is read.
  std::uint64_t total = 0;
  for (const auto &f : files)
  {
    const int depth = declaredDepth (f);
    total += depth > 0 ? (std::uint64_t (1) << depth) - 1 : 0;
    if (total > kMaxForestNodes)
      throw ModelError (f + ": a depth-" + std::to_string (depth) + " tree takes the forest of " +
                        std::to_string (files.size ()) + " files to " + std::to_string (total) + " nodes, more than " +
                        std::to_string (kMaxForestNodes) + " (kMaxForestNodes)");
  }
  ForestBudget budget;
  std::vector<Tree> trees;
  for (const auto &f : files)
    trees.push_back (readTreeFile (f, budget));
  auto forest = std::make_shared<BodyPartForest> (pclClasses (), std::move (trees), kPclFocalLength,
                                                  VoteRule::PclMajority, kPclBackgroundLabel);
  return forest;
}
}  // namespace agex
