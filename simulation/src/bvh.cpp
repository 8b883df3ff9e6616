#include <agex/simulation/bvh.h>
#include <agex/io/input_file.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

namespace agex
{
namespace
{
constexpr int kMaxDepth = 256;
constexpr int kMaxJoints = 10000;

struct Token
{
  std::string text;
  int line = 0;
};

bool
parseNumber (const std::string &text, double &value)
{
  const char *begin = text.data ();
  const char *end = begin + text.size ();
  if (begin != end && *begin == '+')
    ++begin;
  const auto result = std::from_chars (begin, end, value);
  return result.ec == std::errc () && result.ptr == end && std::isfinite (value);
}

bool
equalsIgnoreCase (const std::string &a, const std::string &b)
{
  return a.size () == b.size () &&
         std::equal (a.begin (), a.end (), b.begin (), [] (unsigned char x, unsigned char y) {
           return std::tolower (x) == std::tolower (y);
         });
}

bool
parseChannel (const std::string &text, BvhChannel &channel)
{
  static const BvhChannel all[] = {BvhChannel::Xposition, BvhChannel::Yposition, BvhChannel::Zposition,
                                   BvhChannel::Xrotation, BvhChannel::Yrotation, BvhChannel::Zrotation};
  for (const BvhChannel c : all)
    if (equalsIgnoreCase (text, bvhChannelName (c)))
    {
      channel = c;
      return true;
    }
  return false;
}

/** Splits the lines [0, lines.size()) into whitespace-separated tokens. */
class HierarchyParser
{
public:
  HierarchyParser (const std::string &name, std::vector<Token> tokens, int last_line)
    : name_ (name), tokens_ (std::move (tokens)), last_line_ (last_line)
  {
  }

  std::vector<BvhJoint> parse (int &channel_count)
  {
    expect ("HIERARCHY");
    while (pos_ < tokens_.size ())
    {
      const Token &t = next ("ROOT");
      if (t.text != "ROOT")
        fail (t.line, "expected 'ROOT' or 'MOTION', found '" + t.text + "'");
      parseJoint (t, -1, 0);
    }
    if (joints_.empty ())
      fail (last_line_, "the HIERARCHY has no ROOT joint");
    channel_count = channels_;
    return std::move (joints_);
  }

private:
  [[noreturn]] void fail (int line, const std::string &message) const
  {
    throw BvhError (name_ + ":" + std::to_string (line) + ": " + message);
  }

  const Token &next (const char *what)
  {
    if (pos_ >= tokens_.size ())
      fail (last_line_, std::string ("unexpected end of the HIERARCHY, expected ") + what + " (file truncated?)");
    return tokens_[pos_++];
  }

  const Token *peek () const { return pos_ < tokens_.size () ? &tokens_[pos_] : nullptr; }

  void expect (const char *keyword)
  {
    const Token &t = next ((std::string ("'") + keyword + "'").c_str ());
    if (t.text != keyword)
      fail (t.line, std::string ("expected '") + keyword + "', found '" + t.text + "'");
  }

  double number (const char *what)
  {
    const Token &t = next (what);
    double value;
    if (!parseNumber (t.text, value))
      fail (t.line, std::string ("expected ") + what + ", found '" + t.text + "'");
    return value;
  }

  void parseJoint (const Token &keyword, int parent, int depth)
  {
    if (depth > kMaxDepth)
      fail (keyword.line, "joints nested deeper than " + std::to_string (kMaxDepth));
    if (static_cast<int> (joints_.size ()) >= kMaxJoints)
      fail (keyword.line, "more than " + std::to_string (kMaxJoints) + " joints");
    BvhJoint joint;
    joint.parent = parent;
    joint.line = keyword.line;
    const bool end_site = keyword.text == "End";
    joint.end_site = end_site;
    if (end_site)
    {
      const Token &site = next ("'Site'");
      if (site.text != "Site")
        fail (site.line, "expected 'End Site', found 'End " + site.text + "'");
      joint.name = joints_[parent].name + "/End Site";
    }
    else
    {
      const Token &name = next ("a joint name");
      if (name.text == "{" || name.text == "}")
        fail (name.line, keyword.text + " without a name");
      joint.name = name.text;
    }
    expect ("{");
    const int index = static_cast<int> (joints_.size ());
    joints_.push_back (joint);

    bool have_offset = false, have_channels = false;
    for (;;)
    {
      const Token &t = next ("'}'");
      if (t.text == "}")
        break;
      if (t.text == "OFFSET")
      {
        if (have_offset)
          fail (t.line, "second OFFSET in " + joints_[index].name);
        for (int i = 0; i < 3; ++i)
          joints_[index].offset[i] = number ("three OFFSET values");
        have_offset = true;
      }
      else if (t.text == "CHANNELS")
      {
        if (end_site)
          fail (t.line, "an End Site has no CHANNELS");
        if (have_channels)
          fail (t.line, "second CHANNELS in " + joints_[index].name);
        const double n = number ("the channel count");
        if (n != std::floor (n) || n < 0 || n > 6)
          fail (t.line, "channel count must be 0 to 6, found '" + tokens_[pos_ - 1].text + "'");
        const int count = static_cast<int> (n);
        joints_[index].first_channel = channels_;
        for (int i = 0; i < count; ++i)
        {
          const Token *c = peek ();
          BvhChannel channel;
          if (c == nullptr || !parseChannel (c->text, channel))
            fail (c ? c->line : last_line_,
                  "CHANNELS " + std::to_string (count) + " of " + joints_[index].name + " lists " + std::to_string (i) +
                      " channel names" +
                      (c ? " ('" + c->text + "' is not a channel)" : std::string (" before the file ends (truncated?)")));
          ++pos_;
          for (const BvhChannel previous : joints_[index].channels)
            if (previous == channel)
              fail (c->line, std::string ("channel ") + bvhChannelName (channel) + " listed twice in " +
                                 joints_[index].name);
          joints_[index].channels.push_back (channel);
        }
        {
          BvhChannel extra;
          const Token *c = peek ();
          if (c != nullptr && parseChannel (c->text, extra))
            fail (c->line, "CHANNELS " + std::to_string (count) + " of " + joints_[index].name +
                               " is followed by more channel names than that");
        }
        channels_ += count;
        have_channels = true;
      }
      else if (t.text == "JOINT" || t.text == "End")
      {
        if (end_site)
          fail (t.line, "an End Site has no children");
        if (!have_offset)
          fail (t.line, joints_[index].name + " has no OFFSET before its children");
        parseJoint (t, index, depth + 1);
      }
      else if (t.text == "ROOT" || t.text == "MOTION" || t.text == "HIERARCHY")
        fail (t.line, "'" + t.text + "' inside " + joints_[index].name + " (missing '}'?)");
      else
        fail (t.line, "unexpected '" + t.text + "' in " + joints_[index].name);
    }
    if (!have_offset)
      fail (joints_[index].line, joints_[index].name + " has no OFFSET");
  }

  std::string name_;
  std::vector<Token> tokens_;
  int last_line_;
  std::size_t pos_ = 0;
  std::vector<BvhJoint> joints_;
  int channels_ = 0;
};

Eigen::Matrix3d
axisRotation (BvhChannel channel, double degrees)
{
  const double a = degrees * M_PI / 180.0;
  switch (channel)
  {
    case BvhChannel::Xrotation: return Eigen::AngleAxisd (a, Eigen::Vector3d::UnitX ()).toRotationMatrix ();
    case BvhChannel::Yrotation: return Eigen::AngleAxisd (a, Eigen::Vector3d::UnitY ()).toRotationMatrix ();
    case BvhChannel::Zrotation: return Eigen::AngleAxisd (a, Eigen::Vector3d::UnitZ ()).toRotationMatrix ();
    default: return Eigen::Matrix3d::Identity ();
  }
}

std::vector<std::string>
splitLines (const std::string &text)
{
  std::vector<std::string> lines;
  std::size_t start = 0;
  while (start <= text.size ())
  {
    std::size_t end = text.find ('\n', start);
    if (end == std::string::npos)
      end = text.size ();
    std::string line = text.substr (start, end - start);
    if (!line.empty () && line.back () == '\r')
      line.pop_back ();
    lines.push_back (std::move (line));
    if (end == text.size ())
      break;
    start = end + 1;
  }
  return lines;
}

std::vector<std::string>
words (const std::string &line)
{
  std::vector<std::string> result;
  std::size_t i = 0;
  while (i < line.size ())
  {
    while (i < line.size () && std::isspace (static_cast<unsigned char> (line[i])))
      ++i;
    const std::size_t start = i;
    while (i < line.size () && !std::isspace (static_cast<unsigned char> (line[i])))
      ++i;
    if (i > start)
      result.push_back (line.substr (start, i - start));
  }
  return result;
}
}  // namespace

const char *
bvhChannelName (BvhChannel channel)
{
  switch (channel)
  {
    case BvhChannel::Xposition: return "Xposition";
    case BvhChannel::Yposition: return "Yposition";
    case BvhChannel::Zposition: return "Zposition";
    case BvhChannel::Xrotation: return "Xrotation";
    case BvhChannel::Yrotation: return "Yrotation";
    case BvhChannel::Zrotation: return "Zrotation";
  }
  return "unknown";
}

BvhMotion
BvhMotion::read (const std::string &path)
{
  // Before opening: a FIFO would block until some other process writes to it.
  const std::string problem = notARegularFile (path);
  if (!problem.empty ())
    throw BvhError (path + ": " + problem + "; BVH motion is read from regular files only");
  std::ifstream in (path, std::ios::binary);
  if (!in)
    throw BvhError (path + ": cannot open BVH file (" + std::strerror (errno) + ")");
  std::ostringstream text;
  text << in.rdbuf ();
  if (in.bad ())
    throw BvhError (path + ": cannot read BVH file");
  return parse (text.str (), path);
}

BvhMotion
BvhMotion::parse (const std::string &text, const std::string &name)
{
  const std::vector<std::string> lines = splitLines (text);
  // The HIERARCHY: tokens up to the MOTION keyword.
  std::vector<Token> tokens;
  std::size_t motion_line = lines.size ();
  for (std::size_t i = 0; i < lines.size () && motion_line == lines.size (); ++i)
    for (auto &w : words (lines[i]))
    {
      if (w == "MOTION")
      {
        motion_line = i;
        break;
      }
      tokens.push_back ({std::move (w), static_cast<int> (i + 1)});
    }
  // Where a truncated HIERARCHY is reported: the MOTION line, or the last line with text.
  const int last_line =
      motion_line < lines.size () ? static_cast<int> (motion_line + 1) : (tokens.empty () ? 1 : tokens.back ().line);
  if (tokens.empty () && motion_line == lines.size ())
    throw BvhError (name + ":1: empty file, expected a BVH 'HIERARCHY'");

  BvhMotion motion;
  motion.path_ = name;
  HierarchyParser hierarchy (name, std::move (tokens), last_line);
  motion.joints_ = hierarchy.parse (motion.channel_count_);
  if (motion_line == lines.size ())
    throw BvhError (name + ":" + std::to_string (lines.size ()) +
                    ": no MOTION section after the HIERARCHY (file truncated?)");
  if (words (lines[motion_line]).size () != 1)
    throw BvhError (name + ":" + std::to_string (motion_line + 1) + ": expected 'MOTION' alone on its line");

  // "Frames: N" and "Frame Time: T".
  std::size_t i = motion_line + 1;
  auto header = [&] (const std::vector<std::string> &keyword, const char *what) {
    while (i < lines.size () && words (lines[i]).empty ())
      ++i;
    if (i >= lines.size ())
      throw BvhError (name + ":" + std::to_string (lines.size ()) + ": file ends before '" + what +
                      "' (file truncated?)");
    const std::vector<std::string> w = words (lines[i]);
    double value;
    if (w.size () != keyword.size () + 1 || !std::equal (keyword.begin (), keyword.end (), w.begin ()) ||
        !parseNumber (w.back (), value))
      throw BvhError (name + ":" + std::to_string (i + 1) + ": expected '" + what + " <number>', found '" +
                      lines[i] + "'");
    ++i;
    return value;
  };
  const double frames = header ({"Frames:"}, "Frames:");
  if (frames < 0 || frames != std::floor (frames) || frames > 1e7)
    throw BvhError (name + ":" + std::to_string (i) + ": 'Frames:' must be a non-negative integer");
  motion.frame_count_ = static_cast<int> (frames);
  motion.frame_time_ = header ({"Frame", "Time:"}, "Frame Time:");
  if (!(motion.frame_time_ > 0))
    throw BvhError (name + ":" + std::to_string (i) + ": 'Frame Time:' must be positive");

  const std::size_t nc = static_cast<std::size_t> (motion.channel_count_);
  motion.values_.reserve (nc * motion.frame_count_);
  int read = 0;
  for (; i < lines.size (); ++i)
  {
    const std::string &line = lines[i];
    const char *p = line.data ();
    const char *end = p + line.size ();
    std::size_t count = 0;
    bool blank = true;
    while (p < end)
    {
      while (p < end && std::isspace (static_cast<unsigned char> (*p)))
        ++p;
      if (p >= end)
        break;
      const char *start = p;
      while (p < end && !std::isspace (static_cast<unsigned char> (*p)))
        ++p;
      blank = false;
      if (read >= motion.frame_count_)
        throw BvhError (name + ":" + std::to_string (i + 1) + ": more frames than 'Frames: " +
                        std::to_string (motion.frame_count_) + "'");
      double value;
      if (!parseNumber (std::string (start, p), value))
        throw BvhError (name + ":" + std::to_string (i + 1) + ": '" + std::string (start, p) +
                        "' is not a number (frame " + std::to_string (read) + ")");
      if (count < nc)
        motion.values_.push_back (value);
      ++count;
    }
    if (blank)
      continue;
    if (count != nc)
      throw BvhError (name + ":" + std::to_string (i + 1) + ": frame " + std::to_string (read) + " has " +
                      std::to_string (count) + " values, the HIERARCHY declares " + std::to_string (nc) +
                      " channels");
    ++read;
  }
  if (read != motion.frame_count_)
    throw BvhError (name + ":" + std::to_string (lines.size ()) + ": file ends after " + std::to_string (read) +
                    " of " + std::to_string (motion.frame_count_) + " frames (file truncated?)");
  return motion;
}

int
BvhMotion::findJoint (const std::string &name) const
{
  for (std::size_t i = 0; i < joints_.size (); ++i)
    if (joints_[i].name == name)
      return static_cast<int> (i);
  for (std::size_t i = 0; i < joints_.size (); ++i)
    if (equalsIgnoreCase (joints_[i].name, name))
      return static_cast<int> (i);
  return -1;
}

void
BvhMotion::pose (int frame, double scale, std::vector<Eigen::Isometry3d> &globals) const
{
  if (frame < -1 || frame >= frame_count_)
    throw std::out_of_range (path_ + ": frame " + std::to_string (frame) + " out of range (the file has " +
                             std::to_string (frame_count_) + ")");
  const double *values = frame >= 0 ? this->frame (frame) : nullptr;
  globals.resize (joints_.size ());
  for (std::size_t j = 0; j < joints_.size (); ++j)
  {
    const BvhJoint &joint = joints_[j];
    Eigen::Vector3d translation = joint.offset;
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity ();
    for (std::size_t c = 0; c < joint.channels.size (); ++c)
    {
      const double v = values ? values[joint.first_channel + c] : 0.0;
      switch (joint.channels[c])
      {
        case BvhChannel::Xposition: translation.x () = values ? v : joint.offset.x (); break;
        case BvhChannel::Yposition: translation.y () = values ? v : joint.offset.y (); break;
        case BvhChannel::Zposition: translation.z () = values ? v : joint.offset.z (); break;
        default: rotation = rotation * axisRotation (joint.channels[c], v); break;
      }
    }
    Eigen::Isometry3d local = Eigen::Isometry3d::Identity ();
    local.linear () = rotation;
    local.translation () = translation * scale;
    globals[j] = joint.parent >= 0 ? globals[joint.parent] * local : local;
  }
}

double
BvhMotion::restHeight () const
{
  std::vector<Eigen::Isometry3d> globals;
  pose (-1, 1.0, globals);
  double lo = std::numeric_limits<double>::infinity (), hi = -lo;
  for (const auto &g : globals)
  {
    lo = std::min (lo, g.translation ().y ());
    hi = std::max (hi, g.translation ().y ());
  }
  return globals.empty () ? 0.0 : hi - lo;
}

double
autoBvhScale (const BvhMotion &motion)
{
  const double h = motion.restHeight ();
  if (!(h > 0))
    throw BvhError (motion.path () + ": the rest pose has no height (all joints at one Y); pass the scale explicitly");
  if (h <= 3.0)
    return 1.0;
  if (h <= 60.0)
    return kCmuBvhUnit;
  if (h <= 300.0)
    return 0.01;
  return 0.001;
}
}  // namespace agex
