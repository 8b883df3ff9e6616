#include <agex/simulation/human_mesh.h>
#include <agex/simulation/make_human_targets.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace agex
{
namespace
{
namespace fs = std::filesystem;
constexpr double kDecimetre = 0.1;

/** MakeHuman's macro categories (targets.py _cat_data) and their words. */
const std::set<std::string> &
categoryWords ()
{
  static const std::set<std::string> words = {
      "male",          "female",      "baby",          "child",        "young",         "old",
      "caucasian",     "asian",       "african",       "maxmuscle",    "averagemuscle", "minmuscle",
      "minweight",     "averageweight", "maxweight",   "minheight",    "averageheight", "maxheight"};
  return words;
}

/** The groups modeling_modifiers.json drives by macro variables, checking that those of
  * the macrodetails groups are the ones BodyShape has. */
std::set<std::string>
macroGroups (const fs::path &path)
{
  std::ifstream in (path, std::ios::binary);
  if (!in)
    throw HumanMeshError (path.string () + ": cannot open the file");
  std::ostringstream text;
  text << in.rdbuf ();
  static const std::set<std::string> known = {"Gender", "Age",     "Muscle", "Weight",         "Height",
                                              "African", "Asian", "Caucasian", "BodyProportions"};
  std::set<std::string> groups;
  try
  {
    const nlohmann::json json = nlohmann::json::parse (text.str ());
    if (!json.is_array ())
      throw HumanMeshError (path.string () + ": not MakeHuman modifiers: expected a list of groups");
    for (const auto &group : json)
      for (const auto &modifier : group.at ("modifiers"))
        if (modifier.contains ("macrovar"))
        {
          const std::string variable = modifier.at ("macrovar").get<std::string> ();
          const std::string name = group.at ("group").get<std::string> ();
          // Other groups (the breast's) drive targets outside targets/macrodetails.
          if (name.rfind ("macrodetails", 0) == 0 && !known.count (variable))
            throw HumanMeshError (path.string () + ": macro variable '" + variable +
                                  "' is not one agex::BodyShape knows");
          groups.insert (group.at ("group").get<std::string> ());
        }
  }
  catch (const nlohmann::json::exception &e)
  {
    throw HumanMeshError (path.string () + ": not MakeHuman modifiers: " + e.what ());
  }
  for (const char *required : {"macrodetails", "macrodetails-universal", "macrodetails-height"})
    if (!groups.count (required))
      throw HumanMeshError (path.string () + ": no macro modifier group '" + required + "'");
  return groups;
}

/** Splits a name at '-'. */
std::vector<std::string>
words (const std::string &name)
{
  std::vector<std::string> result;
  std::size_t start = 0;
  while (start <= name.size ())
  {
    const std::size_t end = std::min (name.find ('-', start), name.size ());
    result.push_back (name.substr (start, end - start));
    start = end + 1;
  }
  return result;
}

/** One number of a line, skipping blanks; false if there is none. */
template <typename T>
bool
readNumber (const char *&at, const char *end, T &value)
{
  while (at < end && (*at == ' ' || *at == '\t'))
    ++at;
  const auto [next, error] = std::from_chars (at, end, value);
  if (error != std::errc () || next == at)
    return false;
  at = next;
  return true;
}

MakeHumanTargets::Target
readTarget (const fs::path &path, const fs::path &root, std::size_t vertex_count, const std::set<std::string> &groups)
{
  MakeHumanTargets::Target target;
  target.file = path.string ();
  // Group and factors as MakeHuman's targets.py finds them: folders and non-category
  // words make the group, category words the factors.
  std::vector<std::string> group;
  for (const auto &folder : fs::relative (path.parent_path (), root.parent_path ()))
    group.push_back (folder.string ());
  for (const auto &word : words (path.stem ().string ()))
    if (categoryWords ().count (word))
      target.factors.push_back (word);
    else
      group.push_back (word);
  for (std::size_t i = 0; i < group.size (); ++i)
    target.group += (i ? "-" : "") + group[i];
  if (!groups.count (target.group))
    throw HumanMeshError (target.file + ": its name puts it in group '" + target.group +
                          "', which the modifiers file does not drive by macro variables");

  std::error_code size_error;
  const auto bytes = fs::file_size (path, size_error);
  if (size_error || bytes > MakeHumanTargets::kMaxFileBytes)
    throw HumanMeshError (target.file + ": cannot be read or is larger than " +
                          std::to_string (MakeHumanTargets::kMaxFileBytes >> 20) + " MB");
  std::ifstream in (path, std::ios::binary);
  if (!in)
    throw HumanMeshError (target.file + ": cannot open the file");
  std::vector<char> seen (vertex_count, 0);
  std::string line;
  long number = 0;
  while (std::getline (in, line))
  {
    ++number;
    const char *at = line.data (), *end = at + line.size ();
    while (at < end && (*at == ' ' || *at == '\t'))
      ++at;
    while (end > at && (end[-1] == '\r' || end[-1] == ' ' || end[-1] == '\t'))
      --end;
    if (at == end || *at == '#')
      continue;
    const auto fail = [&] (const std::string &what) {
      throw HumanMeshError (target.file + ":" + std::to_string (number) + ": " + what);
    };
    long index = -1;
    double d[3];
    if (!readNumber (at, end, index) || !readNumber (at, end, d[0]) || !readNumber (at, end, d[1]) ||
        !readNumber (at, end, d[2]))
      fail ("expected 'vertex dx dy dz'");
    while (at < end && (*at == ' ' || *at == '\t'))
      ++at;
    if (at != end)
      fail ("expected 'vertex dx dy dz' and nothing after it");
    if (index < 0 || static_cast<std::size_t> (index) >= vertex_count)
      fail ("vertex " + std::to_string (index) + " is not one of the base mesh's " + std::to_string (vertex_count));
    if (seen[static_cast<std::size_t> (index)])
      fail ("vertex " + std::to_string (index) + " is listed twice");
    seen[static_cast<std::size_t> (index)] = 1;
    for (const double v : d)
      if (!std::isfinite (v) || std::abs (v) > MakeHumanTargets::kMaxOffset)
        fail ("offsets must be finite and at most " + std::to_string (MakeHumanTargets::kMaxOffset) +
              " decimetres");
    target.vertices.push_back (static_cast<int> (index));
    target.offsets.emplace_back (static_cast<float> (d[0]), static_cast<float> (d[1]), static_cast<float> (d[2]));
  }
  return target;
}
}  // namespace

MakeHumanTargets
MakeHumanTargets::load (const std::string &directory, std::size_t vertex_count)
{
  const fs::path dir (directory);
  const std::set<std::string> groups = macroGroups (dir / "modifiers" / "modeling_modifiers.json");
  const fs::path root = dir / "targets" / "macrodetails";
  std::error_code error;
  if (!fs::is_directory (root, error))
    throw HumanMeshError (root.string () + ": no such folder (MakeHuman's macro targets)");
  std::vector<fs::path> files;
  auto collect = [&] (const fs::path &folder, bool descend) {
    for (const auto &entry : fs::directory_iterator (folder))
    {
      if (descend && entry.is_directory ())
        for (const auto &inner : fs::directory_iterator (entry.path ()))
        {
          if (inner.is_regular_file () && inner.path ().extension () == ".target")
            files.push_back (inner.path ());
        }
      else if (entry.is_regular_file () && entry.path ().extension () == ".target")
        files.push_back (entry.path ());
      if (files.size () > static_cast<std::size_t> (kMaxTargets))
        throw HumanMeshError (root.string () + ": more than " + std::to_string (kMaxTargets) + " target files");
    }
  };
  try
  {
    collect (root, true);
  }
  catch (const fs::filesystem_error &e)
  {
    throw HumanMeshError (root.string () + ": cannot list the targets: " + e.what ());
  }
  std::sort (files.begin (), files.end ());  // a fixed order: sums do not depend on the listing
  MakeHumanTargets result;
  result.vertex_count_ = vertex_count;
  std::set<std::string> found;
  for (const auto &file : files)
  {
    result.targets_.push_back (readTarget (file, root, vertex_count, groups));
    found.insert (result.targets_.back ().group);
  }
  for (const char *required : {"macrodetails", "macrodetails-universal", "macrodetails-height"})
    if (!found.count (required))
      throw HumanMeshError (root.string () + ": no targets of group '" + required + "'");
  return result;
}

double
MakeHumanTargets::factor (const std::string &word, const BodyShape &shape)
{
  // human.py: _setGenderVals, _setAgeVals, _setMuscleVals, _setWeightVals, _setHeightVals.
  const auto minOf = [] (double v) { return std::max (0.0, 1.0 - 2.0 * v); };
  const auto maxOf = [] (double v) { return std::max (0.0, 2.0 * v - 1.0); };
  const auto averageOf = [&] (double v) { return 1.0 - minOf (v) - maxOf (v); };
  const double a = shape.age;
  const double young = a < 0.5 ? std::max (0.0, (a - 0.1875) * 3.2) : 1.0 - maxOf (a);
  if (word == "female") return 1.0 - shape.gender;
  if (word == "male") return shape.gender;
  if (word == "old") return a < 0.5 ? 0.0 : maxOf (a);
  if (word == "young") return young;
  if (word == "baby") return a < 0.5 ? std::max (0.0, 1.0 - a * 5.333) : 0.0;
  if (word == "child") return a < 0.5 ? std::max (0.0, std::min (1.0, 5.333 * a) - young) : 0.0;
  if (word == "african") return shape.african;
  if (word == "asian") return shape.asian;
  if (word == "caucasian") return shape.caucasian;
  if (word == "minmuscle") return minOf (shape.muscle);
  if (word == "averagemuscle") return averageOf (shape.muscle);
  if (word == "maxmuscle") return maxOf (shape.muscle);
  if (word == "minweight") return minOf (shape.weight);
  if (word == "averageweight") return averageOf (shape.weight);
  if (word == "maxweight") return maxOf (shape.weight);
  if (word == "minheight") return minOf (shape.height);
  if (word == "averageheight") return averageOf (shape.height);
  if (word == "maxheight") return maxOf (shape.height);
  throw HumanMeshError ("MakeHuman macro category '" + word + "' is unknown");
}

std::vector<double>
MakeHumanTargets::weights (const BodyShape &shape) const
{
  const std::string problem = shape.problem ();
  if (!problem.empty ())
    throw HumanMeshError (problem);
  std::vector<double> result;
  result.reserve (targets_.size ());
  for (const Target &target : targets_)
  {
    double w = 1.0;
    for (const auto &word : target.factors)
      w *= factor (word, shape);
    result.push_back (w);
  }
  return result;
}

std::vector<Eigen::Vector3d>
MakeHumanTargets::offsets (const BodyShape &shape) const
{
  const std::vector<double> w = weights (shape);
  std::vector<Eigen::Vector3d> result (vertex_count_, Eigen::Vector3d::Zero ());
  for (std::size_t t = 0; t < targets_.size (); ++t)
  {
    if (w[t] == 0.0)
      continue;
    const Target &target = targets_[t];
    const double scale = w[t] * kDecimetre;
    for (std::size_t i = 0; i < target.vertices.size (); ++i)
      result[static_cast<std::size_t> (target.vertices[i])] += scale * target.offsets[i].cast<double> ();
  }
  return result;
}
}  // namespace agex
