#include <agex/simulation/human_mesh.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

namespace agex
{
namespace
{
constexpr double kDecimetre = 0.1;  // MakeHuman's files are in decimetres

std::string
readText (const std::filesystem::path &path)
{
  std::ifstream in (path, std::ios::binary);
  if (!in)
    throw HumanMeshError (path.string () + ": cannot open the file");
  std::ostringstream text;
  text << in.rdbuf ();
  return text.str ();
}

nlohmann::json
readJson (const std::filesystem::path &path)
{
  try
  {
    return nlohmann::json::parse (readText (path));
  }
  catch (const nlohmann::json::exception &e)
  {
    throw HumanMeshError (path.string () + ": not valid JSON: " + e.what ());
  }
}

struct Obj
{
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::vector<int>> body_faces;  ///< 0-based, group `body` only
};

Obj
readObj (const std::filesystem::path &path)
{
  std::ifstream in (path);
  if (!in)
    throw HumanMeshError (path.string () + ": cannot open the file");
  Obj obj;
  std::string line, group;
  long number = 0;
  auto fail = [&] (const std::string &what) {
    throw HumanMeshError (path.string () + ":" + std::to_string (number) + ": " + what);
  };
  while (std::getline (in, line))
  {
    ++number;
    if (!line.empty () && line.back () == '\r')
      line.pop_back ();  // CRLF files
    std::istringstream fields (line);
    std::string tag;
    fields >> tag;
    if (tag == "v")
    {
      Eigen::Vector3d v;
      if (!(fields >> v.x () >> v.y () >> v.z ()) || !v.allFinite ())
        fail ("a vertex needs three finite coordinates");
      obj.vertices.push_back (v * kDecimetre);
    }
    else if (tag == "g")
    {
      group.clear ();
      fields >> group;
    }
    else if (tag == "f" && group == "body")
    {
      std::vector<int> face;
      std::string corner;
      while (fields >> corner)
      {
        long index = 0;
        try
        {
          index = std::stol (corner.substr (0, corner.find ('/')));
        }
        catch (const std::exception &)
        {
          fail ("bad face corner '" + corner + "'");
        }
        // Negative indices count back from the last vertex read (OBJ's relative form).
        if (index < 0)
          index += static_cast<long> (obj.vertices.size ()) + 1;
        if (index < 1 || index > static_cast<long> (obj.vertices.size ()))
          fail ("face corner " + corner + " names no vertex read so far");
        face.push_back (static_cast<int> (index - 1));
      }
      if (face.size () < 3)
        fail ("a face needs at least three corners");
      obj.body_faces.push_back (std::move (face));
    }
  }
  if (obj.body_faces.empty ())
    throw HumanMeshError (path.string () + ": no faces in group 'body'");
  return obj;
}

/** A JSON vertex index that fits, or -1. */
long
vertexIndex (const nlohmann::json &value, std::size_t count)
{
  if (!value.is_number_integer ())
    return -1;
  if (value.is_number_unsigned ())
    return value.get<std::uint64_t> () < count ? static_cast<long> (value.get<std::uint64_t> ()) : -1;
  const std::int64_t v = value.get<std::int64_t> ();
  return v >= 0 && static_cast<std::uint64_t> (v) < count ? static_cast<long> (v) : -1;
}

bool
isInSubtree (const std::vector<HumanMesh::Bone> &bones, int bone, int ancestor)
{
  for (int b = bone; b >= 0; b = bones[static_cast<std::size_t> (b)].parent)
    if (b == ancestor)
      return true;
  return false;
}
}  // namespace

int
HumanMesh::bone (const std::string &name) const
{
  for (std::size_t i = 0; i < bones_.size (); ++i)
    if (bones_[i].name == name)
      return static_cast<int> (i);
  return -1;
}

HumanMesh
HumanMesh::load (const std::string &directory)
{
  const std::filesystem::path dir (directory);
  const auto obj_path = dir / "base.obj", skeleton_path = dir / "default.mhskel",
             weights_path = dir / "default_weights.mhw";
  const Obj obj = readObj (obj_path);
  const nlohmann::json skeleton = readJson (skeleton_path), weights = readJson (weights_path);
  HumanMesh mesh;

  // Skeleton: joint positions are the means of their helper vertices.
  try
  {
    const auto &joints = skeleton.at ("joints");
    auto joint = [&] (const std::string &bone, const nlohmann::json &joint_name) {
      const std::string name = joint_name.get<std::string> ();
      if (!joints.contains (name) || !joints.at (name).is_array ())
        throw HumanMeshError (skeleton_path.string () + ": bone '" + bone + "' names joint '" + name +
                              "', which is not a list of vertices under \"joints\"");
      const auto &indices = joints.at (name);
      Eigen::Vector3d sum = Eigen::Vector3d::Zero ();
      for (const auto &i : indices)
      {
        const long v = vertexIndex (i, obj.vertices.size ());
        if (v < 0)
          throw HumanMeshError (skeleton_path.string () + ": joint '" + name + "' names vertex " + i.dump () +
                                ", but " + obj_path.string () + " has " + std::to_string (obj.vertices.size ()));
        sum += obj.vertices[static_cast<std::size_t> (v)];
      }
      if (indices.empty ())
        throw HumanMeshError (skeleton_path.string () + ": joint '" + name + "' has no vertices");
      return Eigen::Vector3d (sum / static_cast<double> (indices.size ()));
    };
    // Parents first: repeatedly take the bones whose parent is placed (names sorted, so
    // the order does not depend on the file's).
    if (!skeleton.is_object () || !joints.is_object () || !skeleton.at ("bones").is_object ())
      throw HumanMeshError (skeleton_path.string () + ": not a MakeHuman skeleton: \"bones\" and \"joints\" must be objects");
    std::map<std::string, nlohmann::json> pending;
    for (const auto &[name, b] : skeleton.at ("bones").items ())
      pending.emplace (name, b);
    std::map<std::string, int> placed;
    while (!pending.empty ())
    {
      bool progress = false;
      for (auto it = pending.begin (); it != pending.end ();)
      {
        const auto &b = it->second;
        const auto &parent = b.at ("parent");
        int parent_index = -1;
        if (!parent.is_null ())
        {
          const auto found = placed.find (parent.get<std::string> ());
          if (found == placed.end ())
          {
            ++it;
            continue;
          }
          parent_index = found->second;
        }
        Bone bone;
        bone.name = it->first;
        bone.parent = parent_index;
        bone.head = joint (bone.name, b.at ("head"));
        bone.tail = joint (bone.name, b.at ("tail"));
        placed.emplace (bone.name, static_cast<int> (mesh.bones_.size ()));
        mesh.bones_.push_back (std::move (bone));
        it = pending.erase (it);
        progress = true;
      }
      if (!progress)
        throw HumanMeshError (skeleton_path.string () + ": bone '" + pending.begin ()->first +
                              "' has a parent that is missing or part of a cycle");
    }
  }
  catch (const nlohmann::json::exception &e)
  {
    throw HumanMeshError (skeleton_path.string () + ": not a MakeHuman skeleton: " + e.what ());
  }
  for (const char *required : {"root", "head", "neck01", "spine03", "spine02", "upperarm01.L", "upperarm01.R",
                               "lowerarm01.L", "lowerarm01.R", "wrist.L", "wrist.R", "finger3-1.L", "finger3-1.R",
                               "upperleg01.L", "upperleg01.R", "lowerleg01.L", "lowerleg01.R", "foot.L", "foot.R",
                               "toe3-1.L", "toe3-1.R"})
    if (mesh.bone (required) < 0)
      throw HumanMeshError (skeleton_path.string () + ": the skeleton has no bone '" + required + "'");

  // The body group's vertices, renumbered (obj_number keeps the file's, for messages).
  std::vector<int> renumber (obj.vertices.size (), -1);
  std::vector<long> obj_number;
  for (const auto &face : obj.body_faces)
    for (const int v : face)
      if (renumber[static_cast<std::size_t> (v)] < 0)
      {
        renumber[static_cast<std::size_t> (v)] = static_cast<int> (mesh.vertices_.size ());
        mesh.vertices_.push_back (obj.vertices[static_cast<std::size_t> (v)]);
        obj_number.push_back (v + 1L);
      }
  for (const auto &face : obj.body_faces)
    for (std::size_t k = 1; k + 1 < face.size (); ++k)
      mesh.triangles_.emplace_back (renumber[static_cast<std::size_t> (face[0])],
                                    renumber[static_cast<std::size_t> (face[k])],
                                    renumber[static_cast<std::size_t> (face[k + 1])]);

  // Skin weights, normalised per vertex.
  mesh.influences_.resize (mesh.vertices_.size ());
  try
  {
    if (!weights.is_object () || !weights.at ("weights").is_object ())
      throw HumanMeshError (weights_path.string () + ": not MakeHuman weights: no \"weights\" object of bones");
    for (const auto &[name, list] : weights.at ("weights").items ())
    {
      if (!list.is_array ())
        throw HumanMeshError (weights_path.string () + ": bone '" + name + "': weights must be a list of [vertex, weight]");
      const int b = mesh.bone (name);
      if (b < 0)
        throw HumanMeshError (weights_path.string () + ": weights for bone '" + name + "', which " +
                              skeleton_path.string () + " does not have");
      for (const auto &pair : list)
      {
        if (!pair.is_array () || pair.size () != 2)
          throw HumanMeshError (weights_path.string () + ": bone '" + name + "': bad weight " + pair.dump () +
                                " (a vertex of " + obj_path.string () + " and a weight >= 0)");
        const long v = vertexIndex (pair.at (0), renumber.size ());
        const double w = pair.at (1).is_number () ? pair.at (1).get<double> () : -1.0;
        if (v < 0 || !(w >= 0.0) || !std::isfinite (w))
          throw HumanMeshError (weights_path.string () + ": bone '" + name + "': bad weight " + pair.dump () +
                                " (a vertex of " + obj_path.string () + " and a weight >= 0)");
        const int r = renumber[static_cast<std::size_t> (v)];
        if (r >= 0 && w > 0.0)
          mesh.influences_[static_cast<std::size_t> (r)].push_back (Influence{b, w});
      }
    }
  }
  catch (const nlohmann::json::exception &e)
  {
    throw HumanMeshError (weights_path.string () + ": not MakeHuman weights: " + e.what ());
  }
  for (std::size_t v = 0; v < mesh.influences_.size (); ++v)
  {
    auto &list = mesh.influences_[v];
    double sum = 0.0;
    for (const auto &i : list)
      sum += i.weight;
    if (!(sum > 0.0))
      throw HumanMeshError (weights_path.string () + ": vertex " + std::to_string (obj_number[v] - 1) + " (line 'v' #" +
                            std::to_string (obj_number[v]) + " of " + obj_path.string () +
                            ", group body) has no skin weight");
    for (auto &i : list)
      i.weight /= sum;
  }

  // Parts, by the bone with the largest weight.
  const int head = mesh.bone ("head");
  const int hands[2] = {mesh.bone ("wrist.L"), mesh.bone ("wrist.R")};
  const int feet[2] = {mesh.bone ("foot.L"), mesh.bone ("foot.R")};
  const int arms[2] = {mesh.bone ("upperarm01.L"), mesh.bone ("upperarm01.R")};
  const int legs[2] = {mesh.bone ("upperleg01.L"), mesh.bone ("upperleg01.R")};
  std::vector<Part> bone_part (mesh.bones_.size (), Trunk);
  for (std::size_t b = 0; b < mesh.bones_.size (); ++b)
  {
    const int bi = static_cast<int> (b);
    if (isInSubtree (mesh.bones_, bi, head))
      bone_part[b] = Head;
    for (int side = 0; side < 2; ++side)
    {
      // Hands and feet lie inside the arm and leg subtrees: test them last.
      if (isInSubtree (mesh.bones_, bi, arms[side]))
        bone_part[b] = side == 0 ? LeftArm : RightArm;
      if (isInSubtree (mesh.bones_, bi, legs[side]))
        bone_part[b] = side == 0 ? LeftLeg : RightLeg;
      if (isInSubtree (mesh.bones_, bi, hands[side]))
        bone_part[b] = side == 0 ? LeftHand : RightHand;
      if (isInSubtree (mesh.bones_, bi, feet[side]))
        bone_part[b] = side == 0 ? LeftFoot : RightFoot;
    }
  }
  mesh.parts_.resize (mesh.vertices_.size ());
  for (std::size_t v = 0; v < mesh.vertices_.size (); ++v)
  {
    const auto &list = mesh.influences_[v];
    const auto top = std::max_element (list.begin (), list.end (),
                                       [] (const Influence &a, const Influence &b) { return a.weight < b.weight; });
    mesh.parts_[v] = bone_part[static_cast<std::size_t> (top->bone)];
  }
  for (const auto &t : mesh.triangles_)
  {
    const Part a = mesh.parts_[static_cast<std::size_t> (t[0])], b = mesh.parts_[static_cast<std::size_t> (t[1])],
               c = mesh.parts_[static_cast<std::size_t> (t[2])];
    mesh.triangle_parts_.push_back (b == c ? b : a);
  }

  // Tips: the top of the head, the farthest point of each hand along the middle
  // finger, the front of each foot.
  auto extreme = [&] (Part part, const Eigen::Vector3d &from, const Eigen::Vector3d &direction) {
    int best = -1;
    double best_value = -std::numeric_limits<double>::infinity ();
    for (std::size_t v = 0; v < mesh.vertices_.size (); ++v)
      if (mesh.parts_[v] == part)
      {
        const double value = (mesh.vertices_[v] - from).dot (direction);
        if (value > best_value)
        {
          best_value = value;
          best = static_cast<int> (v);
        }
      }
    if (best < 0)
      throw HumanMeshError (weights_path.string () + ": no body vertex is weighted mostly to the " +
                            (part == Head ? "head" : part <= RightHand ? "hands" : "feet"));
    return best;
  };
  mesh.tips_.fill (-1);
  mesh.tips_[Head] = extreme (Head, Eigen::Vector3d::Zero (), Eigen::Vector3d::UnitY ());
  for (int side = 0; side < 2; ++side)
  {
    const char *s = side == 0 ? ".L" : ".R";
    const Bone &wrist = mesh.bones_[static_cast<std::size_t> (hands[side])];
    const Bone &finger = mesh.bones_[static_cast<std::size_t> (mesh.bone (std::string ("finger3-1") + s))];
    mesh.tips_[side == 0 ? LeftHand : RightHand] =
        extreme (side == 0 ? LeftHand : RightHand, wrist.head, (finger.head - wrist.head).normalized ());
    const Bone &foot = mesh.bones_[static_cast<std::size_t> (feet[side])];
    const Bone &toe = mesh.bones_[static_cast<std::size_t> (mesh.bone (std::string ("toe3-1") + s))];
    Eigen::Vector3d forward = toe.head - foot.head;
    forward.y () = 0.0;  // the front of the foot, not the sole under the toes
    mesh.tips_[side == 0 ? LeftFoot : RightFoot] = extreme (side == 0 ? LeftFoot : RightFoot, foot.head, forward.normalized ());
  }
  double lowest = std::numeric_limits<double>::infinity (), highest = -lowest;
  for (const auto &v : mesh.vertices_)
  {
    lowest = std::min (lowest, v.y ());
    highest = std::max (highest, v.y ());
  }
  mesh.height_ = highest - lowest;
  if (!(mesh.height_ >= 0.5))
    throw HumanMeshError (obj_path.string () + ": the body is " + std::to_string (mesh.height_) +
                          " m tall (decimetres read as 0.1 m); a standing person is expected");
  return mesh;
}
}  // namespace agex
