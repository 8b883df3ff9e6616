#include <agex/io/dataset.h>
#include <agex/io/input_file.h>

#include <pcl/io/pcd_io.h>

#include <opencv2/imgcodecs.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <set>
#include <sstream>

#include <signal.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace agex
{
namespace
{
constexpr const char *kFormat = "agex-dataset";
constexpr int kVersion = 1;
constexpr const char *kLabelsHeader =
    "frame,part,instance,tip_x,tip_y,tip_z,base_x,base_y,base_z,tip_u,tip_v,base_u,base_v,visible,keyframe";
/** The optional last column: which person of the frame a row labels (1 without it). */
constexpr const char *kPersonColumn = "person";
constexpr const char *kPartLabelFolder = "labels";
constexpr const char *kPersonFolder = "persons";

std::vector<std::string>
splitCsv (const std::string &line)
{
  std::vector<std::string> cells;
  std::string cell;
  std::stringstream in (line);
  while (std::getline (in, cell, ','))
    cells.push_back (cell);
  if (!line.empty () && line.back () == ',')
    cells.emplace_back ();
  return cells;
}

bool
parseFloat (const std::string &text, float &value)
{
  if (text == "nan" || text == "NaN")
  {
    value = std::numeric_limits<float>::quiet_NaN ();
    return true;
  }
  const char *end = text.data () + text.size ();
  const auto result = std::from_chars (text.data (), end, value);
  return result.ec == std::errc () && result.ptr == end && std::isfinite (value);
}

bool
parseInt (const std::string &text, int &value)
{
  const char *end = text.data () + text.size ();
  const auto result = std::from_chars (text.data (), end, value);
  return result.ec == std::errc () && result.ptr == end;
}

bool
validId (const std::string &id)
{
  return !id.empty () && id.size () <= 128 && id != "." && id != ".." &&
         std::all_of (id.begin (), id.end (), [] (unsigned char c) {
           return std::isalnum (c) || c == '_' || c == '-' || c == '.';
         });
}

/** Length of the UTF-8 sequence starting at text[i], 0 if it is not a valid one
  * (overlong forms, surrogates and code points past U+10FFFF are not). */
std::size_t
utf8Length (const std::string &text, std::size_t i)
{
  const auto byte = [&] (std::size_t k) { return static_cast<unsigned char> (text[k]); };
  const unsigned char c = byte (i);
  std::size_t n = 0;
  std::uint32_t code = 0, min = 0;
  if (c < 0x80)
    return 1;
  if ((c & 0xe0) == 0xc0)
    n = 2, code = c & 0x1f, min = 0x80;
  else if ((c & 0xf0) == 0xe0)
    n = 3, code = c & 0x0f, min = 0x800;
  else if ((c & 0xf8) == 0xf0)
    n = 4, code = c & 0x07, min = 0x10000;
  else
    return 0;
  if (i + n > text.size ())
    return 0;
  for (std::size_t k = 1; k < n; ++k)
  {
    if ((byte (i + k) & 0xc0) != 0x80)
      return 0;
    code = (code << 6) | (byte (i + k) & 0x3f);
  }
  if (code < min || code > 0x10ffff || (code >= 0xd800 && code <= 0xdfff))
    return 0;
  return n;
}

/** Whether dataset.json at path says it is an agex dataset (its "format"), read with a bound. */
bool
saysAgexDataset (const fs::path &json_path)
{
  if (!notARegularFile (json_path.string ()).empty ())
    return false;
  std::error_code ec;
  const auto size = fs::file_size (json_path, ec);
  if (ec || size > (std::uintmax_t (256) << 20))
    return false;
  std::ifstream in (json_path, std::ios::binary);
  const nlohmann::json doc = nlohmann::json::parse (in, nullptr, false);
  return doc.is_object () && doc.contains ("format") && doc["format"] == kFormat;
}

std::string
formatFloat (float v)
{
  if (!std::isfinite (v))
    return "nan";
  std::ostringstream out;
  out << std::setprecision (7) << v;
  return out.str ();
}

/** A writer killed (SIGKILL, SIGTERM, power loss) before commit () or its destructor
  * leaves its staging directory <prefix><pid>-XXXXXX beside the target, and, if killed
  * inside commit (), the previous dataset moved aside as <prefix><pid>-XXXXXX.old. The
  * next writer of the same target removes the first and puts the second back, once
  * that process is gone. */
void
recoverInterruptedWriters (const fs::path &target, const std::string &prefix)
{
  std::error_code ec;
  for (const auto &entry : fs::directory_iterator (target.parent_path (), ec))
  {
    const std::string name = entry.path ().filename ().string ();
    if (name.compare (0, prefix.size (), prefix) != 0)
      continue;
    long pid = 0;
    const char *begin = name.data () + prefix.size (), *end = name.data () + name.size ();
    const auto parsed = std::from_chars (begin, end, pid);
    if (parsed.ec != std::errc () || parsed.ptr == end || *parsed.ptr != '-' || pid <= 0 || pid == ::getpid () ||
        ::kill (static_cast<pid_t> (pid), 0) == 0 || errno != ESRCH)
      continue;
    std::error_code ignored;
    const bool moved_aside = name.size () > 4 && name.compare (name.size () - 4, 4, ".old") == 0;
    if (moved_aside && !fs::exists (target, ignored))
      fs::rename (entry.path (), target, ignored);
    else
      fs::remove_all (entry.path (), ignored);
  }
}

template <typename T> T
field (const nlohmann::json &doc, const char *name, const std::string &path)
{
  if (!doc.contains (name))
    throw DatasetError (path + ": missing field '" + name + "'");
  try
  {
    return doc.at (name).get<T> ();
  }
  catch (const nlohmann::json::exception &)
  {
    throw DatasetError (path + ": field '" + name + "' has the wrong type");
  }
}
/** dataset.json's "part_labels": {"1": "head", ...}, ids 1-255 with non-empty names. */
std::map<int, std::string>
parsePartLabels (const nlohmann::json &doc, const std::string &path)
{
  std::map<int, std::string> names;
  if (!doc.contains ("part_labels"))
    return names;
  const nlohmann::json &map = doc.at ("part_labels");
  if (!map.is_object () || map.empty ())
    throw DatasetError (path + ": 'part_labels' must be an object of part ids and names, e.g. {\"1\": \"head\"}");
  for (const auto &[key, value] : map.items ())
  {
    int id = 0;
    if (!parseInt (key, id) || id < 1 || id > 255 || std::to_string (id) != key)
      throw DatasetError (path + ": 'part_labels' id '" + key + "' is not an integer 1-255 (0 is not a body)");
    if (!value.is_string () || value.get<std::string> ().empty () || value.get<std::string> ().size () > 64)
      throw DatasetError (path + ": 'part_labels' " + key + " must be a name of 1-64 characters");
    names[id] = value.get<std::string> ();
  }
  return names;
}

/** An 8-bit single-channel label image of a frame: its size checked from the PNG header
  * before decoding, then its type. */
cv::Mat
loadLabelImage (const std::string &path, int width, int height)
{
  std::error_code ec;
  if (!fs::is_regular_file (path, ec))
    throw DatasetError (path + ": missing (dataset.json says every frame has one)");
  unsigned char head[24] = {};
  std::ifstream in (path, std::ios::binary);
  std::uint64_t w = 0, h = 0;
  if (!in.read (reinterpret_cast<char *> (head), sizeof (head)) || !pngHeaderSize (head, sizeof (head), w, h))
    throw DatasetError (path + ": not a PNG image");
  const std::string expected = std::to_string (width) + "x" + std::to_string (height);
  if (w != static_cast<std::uint64_t> (width) || h != static_cast<std::uint64_t> (height))
    throw DatasetError (path + ": is " + std::to_string (w) + "x" + std::to_string (h) + ", the dataset's frames are " +
                        expected);
  const cv::Mat image = cv::imread (path, cv::IMREAD_UNCHANGED);
  if (image.empty ())
    throw DatasetError (path + ": cannot decode the PNG (truncated or damaged)");
  if (image.type () != CV_8UC1)
    throw DatasetError (path + ": is a " + std::to_string (image.channels ()) + "-channel " +
                        std::to_string (8 * image.elemSize1 ()) + "-bit image; label images are 8-bit, one channel");
  if (image.cols != width || image.rows != height)
    throw DatasetError (path + ": is " + std::to_string (image.cols) + "x" + std::to_string (image.rows) +
                        ", the dataset's frames are " + expected);
  return image;
}
}  // namespace

std::vector<PartLabel>
readLabelsCsv (const std::string &path)
{
  const std::string problem = notARegularFile (path);
  if (!problem.empty ())
    throw DatasetError (path + ": " + problem);
  std::ifstream in (path);
  if (!in)
    throw DatasetError (path + ": cannot open labels file");
  std::string line;
  if (!std::getline (in, line))
    throw DatasetError (path + ":1: empty file, expected the header '" + std::string (kLabelsHeader) + "'");
  if (!line.empty () && line.back () == '\r')
    line.pop_back ();
  const std::string with_person = std::string (kLabelsHeader) + "," + kPersonColumn;
  if (line != kLabelsHeader && line != with_person)
    throw DatasetError (path + ":1: unexpected header, expected '" + std::string (kLabelsHeader) + "', or it and ',"
                        + kPersonColumn + "' for several people per frame");
  const bool has_person = line == with_person;
  const std::size_t columns = has_person ? 16 : 15;

  std::vector<PartLabel> labels;
  std::set<std::tuple<std::string, int, int, int>> seen;
  for (int number = 2; std::getline (in, line); ++number)
  {
    if (!line.empty () && line.back () == '\r')
      line.pop_back ();
    if (line.empty ())
      continue;
    const std::string where = path + ":" + std::to_string (number) + ": ";
    const std::vector<std::string> cells = splitCsv (line);
    if (cells.size () != columns)
      throw DatasetError (where + "expected " + std::to_string (columns) + " comma-separated fields, found " +
                          std::to_string (cells.size ()));
    PartLabel label;
    label.frame = cells[0];
    if (!validId (label.frame))
      throw DatasetError (where + "bad frame id '" + cells[0] + "'");
    if (!parseBodyPart (cells[1], label.part))
      throw DatasetError (where + "unknown part '" + cells[1] + "' (expected head, hand or foot)");
    if (!parseInt (cells[2], label.instance) || label.instance < 0)
      throw DatasetError (where + "instance must be a non-negative integer, got '" + cells[2] + "'");
    float values[10];
    static const char *names[] = {"tip_x", "tip_y", "tip_z", "base_x", "base_y", "base_z",
                                  "tip_u", "tip_v", "base_u", "base_v"};
    for (int i = 0; i < 10; ++i)
      if (!parseFloat (cells[3 + i], values[i]) || (i >= 6 && !std::isfinite (values[i])))
        throw DatasetError (where + names[i] + " is not a number: '" + cells[3 + i] + "'");
    label.tip = Eigen::Vector3f (values[0], values[1], values[2]);
    label.base = Eigen::Vector3f (values[3], values[4], values[5]);
    label.tip_px = Eigen::Vector2f (values[6], values[7]);
    label.base_px = Eigen::Vector2f (values[8], values[9]);
    for (int i : {13, 14})
      if (cells[i] != "0" && cells[i] != "1")
        throw DatasetError (where + (i == 13 ? "visible" : "keyframe") + " must be 0 or 1, got '" + cells[i] + "'");
    label.visible = cells[13] == "1";
    label.keyframe = cells[14] == "1";
    // Scoring needs the tip of every visible label: a NaN there would count as a miss
    // (or make every coverage NaN) instead of being refused.
    if (label.visible && !label.tip.allFinite ())
      throw DatasetError (where + "visible is 1 but the tip is not a number (" + cells[3] + "," + cells[4] + "," +
                          cells[5] + "); a visible label needs its 3D tip (or set visible to 0)");
    if (has_person && (!parseInt (cells[15], label.person) || label.person < 1 || label.person > 255))
      throw DatasetError (where + "person must be an integer 1-255, got '" + cells[15] + "'");
    if (!seen.emplace (label.frame, label.person, static_cast<int> (label.part), label.instance).second)
      throw DatasetError (where + "duplicate label for frame " + label.frame + ", " + cells[1] + " " + cells[2] +
                          (has_person ? ", person " + cells[15] : std::string ()));
    labels.push_back (label);
  }
  return labels;
}

std::string
formatLabelsCsv (const std::vector<PartLabel> &labels)
{
  // The person column only where some frame has another person than the first, so that
  // single-person datasets keep the layout earlier readers know.
  const bool has_person =
      std::any_of (labels.begin (), labels.end (), [] (const PartLabel &l) { return l.person != 1; });
  std::ostringstream out;
  out << kLabelsHeader << (has_person ? std::string (",") + kPersonColumn : std::string ()) << "\n";
  for (const auto &l : labels)
  {
    out << l.frame << "," << bodyPartName (l.part) << "," << l.instance;
    for (int i = 0; i < 3; ++i)
      out << "," << formatFloat (l.tip[i]);
    for (int i = 0; i < 3; ++i)
      out << "," << formatFloat (l.base[i]);
    out << "," << formatFloat (l.tip_px[0]) << "," << formatFloat (l.tip_px[1]) << "," << formatFloat (l.base_px[0])
        << "," << formatFloat (l.base_px[1]) << "," << (l.visible ? 1 : 0) << "," << (l.keyframe ? 1 : 0);
    if (has_person)
      out << "," << l.person;
    out << "\n";
  }
  return out.str ();
}

Dataset
Dataset::read (const std::string &directory)
{
  Dataset ds;
  ds.directory_ = directory;
  std::error_code ec;
  if (!fs::is_directory (directory, ec))
    throw DatasetError (directory + ": not a dataset directory (it does not exist or is not a directory)");
  const std::string json_path = (fs::path (directory) / "dataset.json").string ();
  const std::string problem = notARegularFile (json_path);
  if (!problem.empty ())
    throw DatasetError (json_path + ": " + problem);
  std::ifstream in (json_path);
  if (!in)
    throw DatasetError (json_path + ": missing; every dataset directory has a dataset.json");
  nlohmann::json doc;
  try
  {
    in >> doc;
  }
  catch (const nlohmann::json::exception &e)
  {
    throw DatasetError (json_path + ": not valid JSON (" + e.what () + ")");
  }
  if (!doc.is_object ())
    throw DatasetError (json_path + ": expected a JSON object");
  if (field<std::string> (doc, "format", json_path) != kFormat)
    throw DatasetError (json_path + ": 'format' is not \"" + kFormat + "\"");
  const int version = field<int> (doc, "version", json_path);
  if (version != kVersion)
    throw DatasetError (json_path + ": dataset format version " + std::to_string (version) +
                        " is not supported (this build reads version " + std::to_string (kVersion) + ")");
  DatasetInfo &info = ds.info_;
  info.name = field<std::string> (doc, "name", json_path);
  info.sensor = field<std::string> (doc, "sensor", json_path);
  info.width = field<int> (doc, "width", json_path);
  info.height = field<int> (doc, "height", json_path);
  if (info.width <= 0 || info.height <= 0 || info.width > 100000 || info.height > 100000)
    throw DatasetError (json_path + ": width and height must be positive");
  const auto intr = field<nlohmann::json> (doc, "intrinsics", json_path);
  info.intrinsics.fx = field<double> (intr, "fx", json_path);
  info.intrinsics.fy = field<double> (intr, "fy", json_path);
  info.intrinsics.cx = field<double> (intr, "cx", json_path);
  info.intrinsics.cy = field<double> (intr, "cy", json_path);
  if (!(info.intrinsics.fx > 0) || !(info.intrinsics.fy > 0))
    throw DatasetError (json_path + ": intrinsics fx and fy must be positive");
  info.depth_scale = field<double> (doc, "depth_scale", json_path);
  info.units = field<std::string> (doc, "units", json_path);
  if (info.units != "m")
    throw DatasetError (json_path + ": units must be \"m\" (clouds are stored in metres)");
  info.provenance = doc.value ("provenance", std::string ());
  info.part_labels = parsePartLabels (doc, json_path);
  if (doc.contains ("person_labels"))
    info.person_labels = field<bool> (doc, "person_labels", json_path);

  const auto frames = field<nlohmann::json> (doc, "frames", json_path);
  if (!frames.is_array ())
    throw DatasetError (json_path + ": 'frames' must be an array");
  std::set<std::string> ids;
  for (const auto &f : frames)
  {
    if (!f.is_object ())
      throw DatasetError (json_path + ": each entry of 'frames' must be an object with id and sequence");
    DatasetFrame frame{field<std::string> (f, "id", json_path), field<std::string> (f, "sequence", json_path)};
    if (!validId (frame.id))
      throw DatasetError (json_path + ": bad frame id '" + frame.id + "'");
    if (!ids.insert (frame.id).second)
      throw DatasetError (json_path + ": frame id '" + frame.id + "' listed twice");
    if (!fs::is_regular_file (ds.framePath (frame.id), ec))
      throw DatasetError (ds.framePath (frame.id) + ": listed in dataset.json but missing");
    if (ds.hasPartLabels () && !fs::is_regular_file (ds.partLabelPath (frame.id), ec))
      throw DatasetError (ds.partLabelPath (frame.id) + ": missing (dataset.json lists part_labels, so every frame "
                                                        "has a part-label image)");
    if (ds.hasPersonLabels () && !fs::is_regular_file (ds.personLabelPath (frame.id), ec))
      throw DatasetError (ds.personLabelPath (frame.id) + ": missing (dataset.json says person_labels, so every "
                                                          "frame has a person image)");
    ds.frames_.push_back (frame);
  }

  const std::string labels_path = (fs::path (directory) / "labels.csv").string ();
  ds.labels_ = readLabelsCsv (labels_path);
  for (std::size_t i = 0; i < ds.labels_.size (); ++i)
  {
    if (!ids.count (ds.labels_[i].frame))
      throw DatasetError (labels_path + ": labels frame '" + ds.labels_[i].frame + "', which dataset.json does not list");
    ds.labels_by_frame_[ds.labels_[i].frame].push_back (i);
  }
  return ds;
}

std::vector<PartLabel>
Dataset::labelsOf (const std::string &frame_id) const
{
  std::vector<PartLabel> result;
  const auto it = labels_by_frame_.find (frame_id);
  if (it != labels_by_frame_.end ())
    for (const auto i : it->second)
      result.push_back (labels_[i]);
  return result;
}

bool
Dataset::isKeyframe (const std::string &frame_id) const
{
  for (const auto &l : labelsOf (frame_id))
    if (l.keyframe)
      return true;
  return false;
}

std::string
Dataset::framePath (const std::string &frame_id) const
{
  return (fs::path (directory_) / "frames" / (frame_id + ".pcd")).string ();
}

std::string
Dataset::partLabelPath (const std::string &frame_id) const
{
  return (fs::path (directory_) / kPartLabelFolder / (frame_id + ".png")).string ();
}

std::string
Dataset::personLabelPath (const std::string &frame_id) const
{
  return (fs::path (directory_) / kPersonFolder / (frame_id + ".png")).string ();
}

cv::Mat
Dataset::loadPartLabels (const std::string &frame_id) const
{
  const std::string path = partLabelPath (frame_id);
  if (!hasPartLabels ())
    throw DatasetError (path + ": this dataset has no part-label images (dataset.json lists no part_labels)");
  const cv::Mat image = loadLabelImage (path, info_.width, info_.height);
  for (int v = 0; v < image.rows; ++v)
    for (int u = 0; u < image.cols; ++u)
    {
      const int id = image.at<std::uint8_t> (v, u);
      if (id != 0 && !info_.part_labels.count (id))
        throw DatasetError (path + ": pixel (" + std::to_string (u) + ", " + std::to_string (v) + ") is " +
                            std::to_string (id) + ", which is not a part id of dataset.json's part_labels");
    }
  return image;
}

cv::Mat
Dataset::loadPersonLabels (const std::string &frame_id) const
{
  const std::string path = personLabelPath (frame_id);
  if (!hasPersonLabels ())
    throw DatasetError (path + ": this dataset has no person images (dataset.json has no \"person_labels\": true)");
  return loadLabelImage (path, info_.width, info_.height);
}

pcl::PointCloud<pcl::PointXYZ>::Ptr
Dataset::loadFrame (const std::string &frame_id) const
{
  Frame frame = agex::loadFrame (framePath (frame_id));
  if (static_cast<int> (frame.cloud->width) != info_.width || static_cast<int> (frame.cloud->height) != info_.height)
    throw FrameError (framePath (frame_id) + ": is " + std::to_string (frame.cloud->width) + "x" +
                      std::to_string (frame.cloud->height) + ", the dataset says " + std::to_string (info_.width) +
                      "x" + std::to_string (info_.height));
  return frame.cloud;
}

std::string
datasetReplaceProblem (const std::string &path)
{
  std::error_code ec;
  const fs::file_status status = fs::symlink_status (path, ec);
  if (ec || !fs::exists (status))
    return "";
  if (fs::is_symlink (status))
    return "is a symbolic link, not an agex dataset";
  if (!fs::is_directory (status))
    return std::string (fs::is_regular_file (status) ? "is a regular file" : "is not a directory") +
           ", not an agex dataset";
  const fs::path dir (path);
  if (!saysAgexDataset (dir / "dataset.json"))
    return "is a directory without an agex dataset.json, not an agex dataset";
  // Only what DatasetWriter writes: anything else was put there by someone else.
  const std::map<std::string, std::string> folders = {
      {"frames", ".pcd"}, {kPartLabelFolder, ".png"}, {kPersonFolder, ".png"}};
  for (const auto &entry : fs::directory_iterator (dir, ec))
  {
    const std::string name = entry.path ().filename ().string ();
    const bool ours = (name == "dataset.json" || name == "labels.csv") ? entry.is_regular_file ()
                      : folders.count (name)                             ? entry.is_directory ()
                                                                         : false;
    if (!ours)
      return "holds " + name + ", which is not part of an agex dataset";
  }
  if (ec)
    return "cannot be listed: " + ec.message ();
  for (const auto &[folder, extension] : folders)
  {
    if (!fs::is_directory (dir / folder, ec))
      continue;
    for (const auto &entry : fs::directory_iterator (dir / folder, ec))
      if (!entry.is_regular_file () || entry.path ().extension () != extension)
        return "holds " + folder + "/" + entry.path ().filename ().string () + ", which is not part of an agex dataset";
    if (ec)
      return "cannot be listed: " + ec.message ();
  }
  return "";
}

std::string
enclosingDataset (const std::string &file)
{
  std::error_code ec;
  const fs::path p = fs::weakly_canonical (fs::absolute (file, ec), ec);
  if (ec)
    return "";
  fs::path dir = p.parent_path ();
  if ((dir.filename () == "frames" && p.extension () == ".pcd") ||
      ((dir.filename () == kPartLabelFolder || dir.filename () == kPersonFolder) && p.extension () == ".png"))
    dir = dir.parent_path ();
  else if (p.filename () != "dataset.json" && p.filename () != "labels.csv")
    return "";
  return saysAgexDataset (dir / "dataset.json") ? dir.string () : "";
}

bool
validSequenceName (const std::string &name, std::string *why)
{
  const auto refuse = [&] (const std::string &reason) {
    if (why)
      *why = reason;
    return false;
  };
  for (std::size_t i = 0; i < name.size ();)
  {
    const std::size_t n = utf8Length (name, i);
    if (n == 0)
      return refuse ("is not valid UTF-8");
    const unsigned char c = static_cast<unsigned char> (name[i]);
    if (n == 1 && (c < 0x20 || c == 0x7f))
      return refuse ("holds a control character");
    if (c == ',' || c == '@')
      return refuse (std::string ("holds '") + static_cast<char> (c) + "', which separates sequences in DIR@SEQ,SEQ");
    i += n;
  }
  return true;
}

DatasetWriter::DatasetWriter (const std::string &directory, const DatasetInfo &info, bool overwrite)
  : directory_ (directory), info_ (info), overwrite_ (overwrite)
{
  for (const auto &[id, name] : info.part_labels)
    if (id < 1 || id > 255 || name.empty () || name.size () > 64)
      throw DatasetError (directory + ": part label " + std::to_string (id) + " '" + name +
                          "': ids are 1-255 (0 is not a body), names 1-64 characters");
  std::error_code ec;
  if (fs::exists (fs::symlink_status (directory, ec)) && !overwrite)
    throw DatasetError (directory + ": already exists; pass --force to replace it");
  if (overwrite)
  {
    const std::string problem = datasetReplaceProblem (directory);
    if (!problem.empty ())
      throw DatasetError (directory + ": " + problem + "; only an earlier agex dataset is replaced");
  }
  const fs::path target = fs::absolute (directory);
  fs::create_directories (target.parent_path (), ec);
  const std::string prefix = "." + target.filename ().string () + ".partial-";
  recoverInterruptedWriters (target, prefix);
  // The writer's process id is in the name, so that a later writer can tell an
  // abandoned staging directory (its process was killed) from a live one.
  std::string tmpl = (target.parent_path () / (prefix + std::to_string (::getpid ()) + "-XXXXXX")).string ();
  if (!::mkdtemp (tmpl.data ()))
    throw DatasetError (directory + ": cannot create a staging directory beside it");
  staging_ = tmpl;
  fs::create_directories (fs::path (staging_) / "frames", ec);
  if (ec)
    throw DatasetError (staging_ + ": cannot create frames/: " + ec.message ());
}

DatasetWriter::~DatasetWriter ()
{
  if (!committed_ && !staging_.empty ())
  {
    std::error_code ec;
    fs::remove_all (staging_, ec);
  }
}

namespace
{
template <typename PointT>
void
writeFrameFile (const std::string &path, const pcl::PointCloud<PointT> &cloud)
{
  if (pcl::io::savePCDFileBinaryCompressed (path, cloud) != 0)
    throw DatasetError (path + ": cannot write frame");
}
}  // namespace

std::string
DatasetWriter::framePath (const std::string &id, std::uint32_t width, std::uint32_t height) const
{
  if (!validId (id))
    throw DatasetError ("bad frame id '" + id + "' (letters, digits, '_', '-', '.')");
  if (std::any_of (frames_.begin (), frames_.end (), [&] (const DatasetFrame &f) { return f.id == id; }))
    throw DatasetError ("frame id '" + id + "' added twice");
  if (static_cast<int> (width) != info_.width || static_cast<int> (height) != info_.height)
    throw DatasetError ("frame '" + id + "' is " + std::to_string (width) + "x" + std::to_string (height) +
                        ", the dataset is " + std::to_string (info_.width) + "x" + std::to_string (info_.height));
  return (fs::path (staging_) / "frames" / (id + ".pcd")).string ();
}

void
DatasetWriter::checkLabels (const std::string &id, const std::vector<PartLabel> &labels) const
{
  for (const PartLabel &label : labels)
    if (label.person < 1 || label.person > 255)
      throw DatasetError ("frame '" + id + "': a label's person is " + std::to_string (label.person) +
                          "; persons are 1-255");
}

void
DatasetWriter::addLabels (const std::string &id, const std::string &sequence, const std::vector<PartLabel> &labels)
{
  std::string why;
  if (!validSequenceName (sequence, &why))
    throw DatasetError ("frame '" + id + "': the sequence name '" + sequence + "' " + why);
  for (const auto &label : labels)
    if (label.visible && !label.tip.allFinite ())
      throw DatasetError ("frame '" + id + "': a visible label without a finite tip");
  frames_.push_back ({id, sequence});
  for (PartLabel label : labels)
  {
    label.frame = id;
    labels_.push_back (label);
  }
}

void
DatasetWriter::addImage (const std::string &id, const cv::Mat &image, const char *folder, const char *what,
                         std::set<std::string> &added)
{
  if (std::none_of (frames_.begin (), frames_.end (), [&] (const DatasetFrame &f) { return f.id == id; }))
    throw DatasetError (std::string (what) + " for frame '" + id + "', which was not added");
  if (added.count (id))
    throw DatasetError (std::string (what) + " for frame '" + id + "' added twice");
  if (image.type () != CV_8UC1 || image.cols != info_.width || image.rows != info_.height)
    throw DatasetError (std::string (what) + " for frame '" + id + "' must be 8-bit, one channel, " +
                        std::to_string (info_.width) + "x" + std::to_string (info_.height));
  const fs::path dir = fs::path (staging_) / folder;
  std::error_code ec;
  fs::create_directories (dir, ec);
  const std::string path = (dir / (id + ".png")).string ();
  bool written = false;
  try
  {
    written = cv::imwrite (path, image);
  }
  catch (const cv::Exception &)
  {
  }
  if (!written)
    throw DatasetError (path + ": cannot write the " + what);
  added.insert (id);
}

void
DatasetWriter::addPartLabels (const std::string &id, const cv::Mat &labels)
{
  if (info_.part_labels.empty ())
    throw DatasetError ("part-label image for frame '" + id + "', but the dataset info names no part_labels");
  for (int v = 0; v < labels.rows; ++v)
    for (int u = 0; u < labels.cols && labels.type () == CV_8UC1; ++u)
    {
      const int value = labels.at<std::uint8_t> (v, u);
      if (value != 0 && !info_.part_labels.count (value))
        throw DatasetError ("part-label image for frame '" + id + "': pixel (" + std::to_string (u) + ", " +
                            std::to_string (v) + ") is " + std::to_string (value) + ", not a part id of part_labels");
    }
  addImage (id, labels, kPartLabelFolder, "part-label image", part_label_ids_);
}

void
DatasetWriter::addPersonLabels (const std::string &id, const cv::Mat &persons)
{
  addImage (id, persons, kPersonFolder, "person image", person_ids_);
}

void
DatasetWriter::addFrame (const std::string &id, const std::string &sequence,
                         const pcl::PointCloud<pcl::PointXYZ> &cloud, const std::vector<PartLabel> &labels)
{
  checkLabels (id, labels);
  writeFrameFile (framePath (id, cloud.width, cloud.height), cloud);
  addLabels (id, sequence, labels);
}

void
DatasetWriter::addFrame (const std::string &id, const std::string &sequence,
                         const pcl::PointCloud<pcl::PointXYZRGBA> &cloud, const std::vector<PartLabel> &labels)
{
  checkLabels (id, labels);
  writeFrameFile (framePath (id, cloud.width, cloud.height), cloud);
  addLabels (id, sequence, labels);
}

void
DatasetWriter::commit ()
{
  if (!info_.part_labels.empty () && part_label_ids_.size () != frames_.size ())
    throw DatasetError (directory_ + ": " + std::to_string (frames_.size () - part_label_ids_.size ()) + " of " +
                        std::to_string (frames_.size ()) + " frames have no part-label image; every frame needs one");
  if (!person_ids_.empty () && person_ids_.size () != frames_.size ())
    throw DatasetError (directory_ + ": " + std::to_string (frames_.size () - person_ids_.size ()) + " of " +
                        std::to_string (frames_.size ()) + " frames have no person image; every frame needs one");
  nlohmann::json doc;
  doc["format"] = kFormat;
  doc["version"] = kVersion;
  doc["name"] = info_.name;
  doc["sensor"] = info_.sensor;
  doc["width"] = info_.width;
  doc["height"] = info_.height;
  doc["intrinsics"] = {{"fx", info_.intrinsics.fx}, {"fy", info_.intrinsics.fy},
                       {"cx", info_.intrinsics.cx}, {"cy", info_.intrinsics.cy}};
  doc["depth_scale"] = info_.depth_scale;
  doc["units"] = "m";
  doc["provenance"] = info_.provenance;
  if (!info_.part_labels.empty ())
  {
    doc["part_labels"] = nlohmann::json::object ();
    for (const auto &[id, name] : info_.part_labels)
      doc["part_labels"][std::to_string (id)] = name;
  }
  if (!person_ids_.empty ())
    doc["person_labels"] = true;
  doc["frames"] = nlohmann::json::array ();
  for (const auto &f : frames_)
    doc["frames"].push_back ({{"id", f.id}, {"sequence", f.sequence}});
  {
    std::ofstream json (fs::path (staging_) / "dataset.json");
    json << doc.dump (2) << "\n";
    std::ofstream csv (fs::path (staging_) / "labels.csv");
    csv << formatLabelsCsv (labels_);
    if (!json || !csv)
      throw DatasetError (staging_ + ": cannot write dataset.json or labels.csv");
  }
  std::error_code ec;
  std::string old;
  if (fs::exists (fs::symlink_status (directory_, ec)))
  {
    if (!overwrite_)
      throw DatasetError (directory_ + ": appeared while converting; not replaced");
    // Checked again: it may have changed while the frames were written.
    const std::string problem = datasetReplaceProblem (directory_);
    if (!problem.empty ())
      throw DatasetError (directory_ + ": " + problem + "; only an earlier agex dataset is replaced");
    old = staging_ + ".old";
    fs::rename (directory_, old, ec);
    if (ec)
      throw DatasetError (directory_ + ": cannot move the old dataset aside: " + ec.message ());
  }
  fs::rename (staging_, directory_, ec);
  if (ec)
  {
    if (!old.empty ())
      fs::rename (old, directory_);
    throw DatasetError (directory_ + ": cannot move the new dataset into place: " + ec.message ());
  }
  committed_ = true;
  if (!old.empty ())
    fs::remove_all (old, ec);
}
}  // namespace agex
