#include <agex/simulation/human_mesh.h>
#include <agex/simulation/make_human_targets.h>

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
/** The three files of a MakeHuman directory. */
struct AssetPaths
{
  std::filesystem::path obj, skeleton, weights;
};

int
boneIndex (const std::vector<HumanMesh::Bone> &bones, const std::string &name)
{
  for (std::size_t i = 0; i < bones.size (); ++i)
    if (bones[i].name == name)
      return static_cast<int> (i);
  return -1;
}

/** A joint's position: the mean of its helper vertices, listed under "joints". */
Eigen::Vector3d
jointPosition (const nlohmann::json &joints, const std::string &bone, const nlohmann::json &joint_name,
               const Obj &obj, const AssetPaths &paths, std::vector<int> &vertices)
{
  const std::string name = joint_name.get<std::string> ();
  if (!joints.contains (name) || !joints.at (name).is_array ())
    throw HumanMeshError (paths.skeleton.string () + ": bone '" + bone + "' names joint '" + name +
                          "', which is not a list of vertices under \"joints\"");
  const auto &indices = joints.at (name);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero ();
  for (const auto &i : indices)
  {
    const long v = vertexIndex (i, obj.vertices.size ());
    if (v < 0)
      throw HumanMeshError (paths.skeleton.string () + ": joint '" + name + "' names vertex " + i.dump () + ", but " +
                            paths.obj.string () + " has " + std::to_string (obj.vertices.size ()));
    sum += obj.vertices[static_cast<std::size_t> (v)];
    vertices.push_back (static_cast<int> (v));
  }
  if (indices.empty ())
    throw HumanMeshError (paths.skeleton.string () + ": joint '" + name + "' has no vertices");
  return Eigen::Vector3d (sum / static_cast<double> (indices.size ()));
}

/** The skeleton's bones, parents first: repeatedly take the bones whose parent is
  * placed (names sorted, so the order does not depend on the file's). */
std::vector<HumanMesh::Bone>
readBones (const nlohmann::json &skeleton, const Obj &obj, const AssetPaths &paths,
           std::vector<std::vector<int>> &joint_vertices)
{
  std::vector<HumanMesh::Bone> bones;
  try
  {
    const auto &joints = skeleton.at ("joints");
    if (!skeleton.is_object () || !joints.is_object () || !skeleton.at ("bones").is_object ())
      throw HumanMeshError (paths.skeleton.string () +
                            ": not a MakeHuman skeleton: \"bones\" and \"joints\" must be objects");
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
        HumanMesh::Bone bone;
        bone.name = it->first;
        bone.parent = parent_index;
        joint_vertices.emplace_back ();
        bone.head = jointPosition (joints, bone.name, b.at ("head"), obj, paths, joint_vertices.back ());
        joint_vertices.emplace_back ();
        bone.tail = jointPosition (joints, bone.name, b.at ("tail"), obj, paths, joint_vertices.back ());
        placed.emplace (bone.name, static_cast<int> (bones.size ()));
        bones.push_back (std::move (bone));
        it = pending.erase (it);
        progress = true;
      }
      if (!progress)
        throw HumanMeshError (paths.skeleton.string () + ": bone '" + pending.begin ()->first +
                              "' has a parent that is missing or part of a cycle");
    }
  }
  catch (const nlohmann::json::exception &e)
  {
    throw HumanMeshError (paths.skeleton.string () + ": not a MakeHuman skeleton: " + e.what ());
  }
  return bones;
}

/** The bones the body is posed, shaped and labelled by. */
void
requireBones (const std::vector<HumanMesh::Bone> &bones, const AssetPaths &paths)
{
  for (const char *required : {"root", "head", "neck01", "spine03", "spine02", "upperarm01.L", "upperarm01.R",
                               "lowerarm01.L", "lowerarm01.R", "wrist.L", "wrist.R", "finger3-1.L", "finger3-1.R",
                               "upperleg01.L", "upperleg01.R", "lowerleg01.L", "lowerleg01.R", "foot.L", "foot.R",
                               "toe3-1.L", "toe3-1.R"})
    if (boneIndex (bones, required) < 0)
      throw HumanMeshError (paths.skeleton.string () + ": the skeleton has no bone '" + required + "'");
}

/** The body group's vertices, renumbered in the order the faces use them, and its
  * faces split into triangles (fans). */
struct BodyGroup
{
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> triangles;
  std::vector<int> renumber;     ///< per OBJ vertex (0-based): its body vertex, -1 if none
  std::vector<long> obj_number;  ///< per body vertex: its 1-based OBJ number, for messages
};

BodyGroup
bodyGroup (const Obj &obj)
{
  BodyGroup body;
  body.renumber.assign (obj.vertices.size (), -1);
  for (const auto &face : obj.body_faces)
    for (const int v : face)
      if (body.renumber[static_cast<std::size_t> (v)] < 0)
      {
        body.renumber[static_cast<std::size_t> (v)] = static_cast<int> (body.vertices.size ());
        body.vertices.push_back (obj.vertices[static_cast<std::size_t> (v)]);
        body.obj_number.push_back (v + 1L);
      }
  for (const auto &face : obj.body_faces)
    for (std::size_t k = 1; k + 1 < face.size (); ++k)
      body.triangles.emplace_back (body.renumber[static_cast<std::size_t> (face[0])],
                                   body.renumber[static_cast<std::size_t> (face[k])],
                                   body.renumber[static_cast<std::size_t> (face[k + 1])]);
  return body;
}

/** The skin weights of the body's vertices (weights of other vertices are skipped). */
std::vector<std::vector<HumanMesh::Influence>>
readInfluences (const nlohmann::json &weights, const std::vector<HumanMesh::Bone> &bones, const BodyGroup &body,
                const AssetPaths &paths)
{
  std::vector<std::vector<HumanMesh::Influence>> influences (body.vertices.size ());
  try
  {
    if (!weights.is_object () || !weights.at ("weights").is_object ())
      throw HumanMeshError (paths.weights.string () + ": not MakeHuman weights: no \"weights\" object of bones");
    for (const auto &[name, list] : weights.at ("weights").items ())
    {
      if (!list.is_array ())
        throw HumanMeshError (paths.weights.string () + ": bone '" + name +
                              "': weights must be a list of [vertex, weight]");
      const int b = boneIndex (bones, name);
      if (b < 0)
        throw HumanMeshError (paths.weights.string () + ": weights for bone '" + name + "', which " +
                              paths.skeleton.string () + " does not have");
      for (const auto &pair : list)
      {
        if (!pair.is_array () || pair.size () != 2)
          throw HumanMeshError (paths.weights.string () + ": bone '" + name + "': bad weight " + pair.dump () +
                                " (a vertex of " + paths.obj.string () + " and a weight >= 0)");
        const long v = vertexIndex (pair.at (0), body.renumber.size ());
        const double w = pair.at (1).is_number () ? pair.at (1).get<double> () : -1.0;
        if (v < 0 || !(w >= 0.0) || !std::isfinite (w))
          throw HumanMeshError (paths.weights.string () + ": bone '" + name + "': bad weight " + pair.dump () +
                                " (a vertex of " + paths.obj.string () + " and a weight >= 0)");
        const int r = body.renumber[static_cast<std::size_t> (v)];
        if (r >= 0 && w > 0.0)
          influences[static_cast<std::size_t> (r)].push_back (HumanMesh::Influence{b, w});
      }
    }
  }
  catch (const nlohmann::json::exception &e)
  {
    throw HumanMeshError (paths.weights.string () + ": not MakeHuman weights: " + e.what ());
  }
  return influences;
}

/** Scales each vertex's weights to sum to 1; a vertex without weight is an error. */
void
normaliseInfluences (std::vector<std::vector<HumanMesh::Influence>> &influences, const BodyGroup &body,
                     const AssetPaths &paths)
{
  for (std::size_t v = 0; v < influences.size (); ++v)
  {
    auto &list = influences[v];
    double sum = 0.0;
    for (const auto &i : list)
      sum += i.weight;
    if (!(sum > 0.0))
      throw HumanMeshError (paths.weights.string () + ": vertex " + std::to_string (body.obj_number[v] - 1) +
                            " (line 'v' #" + std::to_string (body.obj_number[v]) + " of " + paths.obj.string () +
                            ", group body) has no skin weight");
    for (auto &i : list)
      i.weight /= sum;
  }
}

/** The part each bone belongs to, by the subtree it lies in. */
std::vector<HumanMesh::Part>
boneParts (const std::vector<HumanMesh::Bone> &bones)
{
  const int head = boneIndex (bones, "head");
  const int hands[2] = {boneIndex (bones, "wrist.L"), boneIndex (bones, "wrist.R")};
  const int feet[2] = {boneIndex (bones, "foot.L"), boneIndex (bones, "foot.R")};
  const int arms[2] = {boneIndex (bones, "upperarm01.L"), boneIndex (bones, "upperarm01.R")};
  const int legs[2] = {boneIndex (bones, "upperleg01.L"), boneIndex (bones, "upperleg01.R")};
  std::vector<HumanMesh::Part> bone_part (bones.size (), HumanMesh::Trunk);
  for (std::size_t b = 0; b < bones.size (); ++b)
  {
    const int bi = static_cast<int> (b);
    if (isInSubtree (bones, bi, head))
      bone_part[b] = HumanMesh::Head;
    for (int side = 0; side < 2; ++side)
    {
      // Hands and feet lie inside the arm and leg subtrees: test them last.
      if (isInSubtree (bones, bi, arms[side]))
        bone_part[b] = side == 0 ? HumanMesh::LeftArm : HumanMesh::RightArm;
      if (isInSubtree (bones, bi, legs[side]))
        bone_part[b] = side == 0 ? HumanMesh::LeftLeg : HumanMesh::RightLeg;
      if (isInSubtree (bones, bi, hands[side]))
        bone_part[b] = side == 0 ? HumanMesh::LeftHand : HumanMesh::RightHand;
      if (isInSubtree (bones, bi, feet[side]))
        bone_part[b] = side == 0 ? HumanMesh::LeftFoot : HumanMesh::RightFoot;
    }
  }
  return bone_part;
}

/** Each vertex's part: that of the bone with the largest weight. */
std::vector<HumanMesh::Part>
vertexParts (const std::vector<std::vector<HumanMesh::Influence>> &influences,
             const std::vector<HumanMesh::Part> &bone_part)
{
  std::vector<HumanMesh::Part> parts (influences.size ());
  for (std::size_t v = 0; v < influences.size (); ++v)
  {
    const auto &list = influences[v];
    const auto top = std::max_element (list.begin (), list.end (), [] (const HumanMesh::Influence &a,
                                                                       const HumanMesh::Influence &b) {
      return a.weight < b.weight;
    });
    parts[v] = bone_part[static_cast<std::size_t> (top->bone)];
  }
  return parts;
}

/** Each triangle's part: that of its second and third corners if they agree, else the
  * first's (so that of most of its corners). */
std::vector<HumanMesh::Part>
partsOfTriangles (const std::vector<Eigen::Vector3i> &triangles, const std::vector<HumanMesh::Part> &parts)
{
  std::vector<HumanMesh::Part> result;
  for (const auto &t : triangles)
  {
    const HumanMesh::Part a = parts[static_cast<std::size_t> (t[0])], b = parts[static_cast<std::size_t> (t[1])],
                          c = parts[static_cast<std::size_t> (t[2])];
    result.push_back (b == c ? b : a);
  }
  return result;
}

/** The per-pixel label part of each bone (HumanMesh::boneLabels). */
std::vector<SynthPart>
labelBones (const std::vector<HumanMesh::Bone> &bones)
{
  struct Subtree
  {
    const char *bone;
    SynthPart left, right;  ///< for a sided bone (name + ".L" / ".R"); left for a middle one
  };
  // Outer subtrees first, so that the inner ones (a hand in its arm) win.
  static const Subtree subtrees[] = {
      {"neck01", SynthPart::Neck, SynthPart::Neck},
      {"head", SynthPart::Head, SynthPart::Head},
      {"upperarm01", SynthPart::LeftUpperArm, SynthPart::RightUpperArm},
      {"lowerarm01", SynthPart::LeftForearm, SynthPart::RightForearm},
      {"wrist", SynthPart::LeftHand, SynthPart::RightHand},
      {"upperleg01", SynthPart::LeftThigh, SynthPart::RightThigh},
      {"lowerleg01", SynthPart::LeftLowerLeg, SynthPart::RightLowerLeg},
      {"foot", SynthPart::LeftFoot, SynthPart::RightFoot}};
  std::vector<SynthPart> labels (bones.size (), SynthPart::Torso);
  for (const char *pelvis : {"root", "spine05", "pelvis.L", "pelvis.R"})
  {
    const int b = boneIndex (bones, pelvis);
    if (b >= 0)
      labels[static_cast<std::size_t> (b)] = SynthPart::Pelvis;
  }
  for (const Subtree &subtree : subtrees)
  {
    const bool sided = subtree.left != subtree.right;
    for (int side = 0; side < (sided ? 2 : 1); ++side)
    {
      const int top = boneIndex (bones, std::string (subtree.bone) + (sided ? (side == 0 ? ".L" : ".R") : ""));
      if (top < 0)
        continue;
      for (std::size_t b = 0; b < bones.size (); ++b)
        if (isInSubtree (bones, static_cast<int> (b), top))
          labels[b] = side == 0 ? subtree.left : subtree.right;
    }
  }
  return labels;
}

/** Each triangle's label: that of the bone with the largest weight over its corners. */
std::vector<SynthPart>
labelTriangles (const std::vector<Eigen::Vector3i> &triangles,
                const std::vector<std::vector<HumanMesh::Influence>> &influences,
                const std::vector<SynthPart> &bone_labels)
{
  std::vector<SynthPart> labels;
  labels.reserve (triangles.size ());
  std::map<int, double> weight;  // ordered by bone: ties go to the first
  for (const auto &t : triangles)
  {
    weight.clear ();
    for (int k = 0; k < 3; ++k)
      for (const auto &influence : influences[static_cast<std::size_t> (t[k])])
        weight[influence.bone] += influence.weight;
    int best = weight.begin ()->first;
    for (const auto &[bone, w] : weight)
      if (w > weight[best])
        best = bone;
    labels.push_back (bone_labels[static_cast<std::size_t> (best)]);
  }
  return labels;
}

/** The vertex of a part farthest along a direction from a point. */
int
extremeVertex (const std::vector<Eigen::Vector3d> &vertices, const std::vector<HumanMesh::Part> &parts,
               HumanMesh::Part part, const Eigen::Vector3d &from, const Eigen::Vector3d &direction,
               const AssetPaths &paths)
{
  int best = -1;
  double best_value = -std::numeric_limits<double>::infinity ();
  for (std::size_t v = 0; v < vertices.size (); ++v)
    if (parts[v] == part)
    {
      const double value = (vertices[v] - from).dot (direction);
      if (value > best_value)
      {
        best_value = value;
        best = static_cast<int> (v);
      }
    }
  if (best < 0)
    throw HumanMeshError (paths.weights.string () + ": no body vertex is weighted mostly to the " +
                          (part == HumanMesh::Head ? "head" : part <= HumanMesh::RightHand ? "hands" : "feet"));
  return best;
}

/** Tips: the top of the head, the farthest point of each hand along the middle
  * finger, the front of each foot; -1 for the other parts. */
std::array<int, HumanMesh::kParts>
findTipVertices (const std::vector<Eigen::Vector3d> &vertices, const std::vector<HumanMesh::Part> &parts,
             const std::vector<HumanMesh::Bone> &bones, const AssetPaths &paths)
{
  std::array<int, HumanMesh::kParts> tips;
  tips.fill (-1);
  tips[HumanMesh::Head] =
      extremeVertex (vertices, parts, HumanMesh::Head, Eigen::Vector3d::Zero (), Eigen::Vector3d::UnitY (), paths);
  for (int side = 0; side < 2; ++side)
  {
    const std::string s = side == 0 ? ".L" : ".R";
    const HumanMesh::Part hand = side == 0 ? HumanMesh::LeftHand : HumanMesh::RightHand;
    const HumanMesh::Part foot_part = side == 0 ? HumanMesh::LeftFoot : HumanMesh::RightFoot;
    const HumanMesh::Bone &wrist = bones[static_cast<std::size_t> (boneIndex (bones, "wrist" + s))];
    const HumanMesh::Bone &finger = bones[static_cast<std::size_t> (boneIndex (bones, "finger3-1" + s))];
    tips[hand] = extremeVertex (vertices, parts, hand, wrist.head, (finger.head - wrist.head).normalized (), paths);
    const HumanMesh::Bone &foot = bones[static_cast<std::size_t> (boneIndex (bones, "foot" + s))];
    const HumanMesh::Bone &toe = bones[static_cast<std::size_t> (boneIndex (bones, "toe3-1" + s))];
    Eigen::Vector3d forward = toe.head - foot.head;
    forward.y () = 0.0;  // the front of the foot, not the sole under the toes
    tips[foot_part] = extremeVertex (vertices, parts, foot_part, foot.head, forward.normalized (), paths);
  }
  return tips;
}

/** Rest-pose height (Y extent of the vertices); a standing person is expected. */
double
standingHeight (const std::vector<Eigen::Vector3d> &vertices, const AssetPaths &paths)
{
  double lowest = std::numeric_limits<double>::infinity (), highest = -lowest;
  for (const auto &v : vertices)
  {
    lowest = std::min (lowest, v.y ());
    highest = std::max (highest, v.y ());
  }
  const double height = highest - lowest;
  if (!(height >= 0.5))
    throw HumanMeshError (paths.obj.string () + ": the body is " + std::to_string (height) +
                          " m tall (decimetres read as 0.1 m); a standing person is expected");
  return height;
}
}  // namespace

int
HumanMesh::bone (const std::string &name) const
{
  return boneIndex (bones_, name);
}

namespace
{
AssetPaths
assetPaths (const std::string &directory)
{
  const std::filesystem::path dir (directory);
  return AssetPaths{dir / "base.obj", dir / "default.mhskel", dir / "default_weights.mhw"};
}
}  // namespace

HumanMesh
HumanMesh::load (const std::string &directory)
{
  const AssetPaths paths = assetPaths (directory);
  const Obj obj = readObj (paths.obj);
  const nlohmann::json skeleton = readJson (paths.skeleton), weights = readJson (paths.weights);

  HumanMesh mesh;
  mesh.directory_ = directory;
  mesh.bones_ = readBones (skeleton, obj, paths, mesh.joint_vertices_);
  requireBones (mesh.bones_, paths);
  BodyGroup body = bodyGroup (obj);
  mesh.influences_ = readInfluences (weights, mesh.bones_, body, paths);
  normaliseInfluences (mesh.influences_, body, paths);
  mesh.vertices_ = std::move (body.vertices);
  mesh.base_vertices_ = obj.vertices;
  mesh.body_vertex_source_.reserve (body.obj_number.size ());
  for (const long number : body.obj_number)
    mesh.body_vertex_source_.push_back (static_cast<int> (number - 1));
  mesh.triangles_ = std::move (body.triangles);
  mesh.parts_ = vertexParts (mesh.influences_, boneParts (mesh.bones_));
  mesh.triangle_parts_ = partsOfTriangles (mesh.triangles_, mesh.parts_);
  mesh.bone_labels_ = labelBones (mesh.bones_);
  mesh.triangle_labels_ = labelTriangles (mesh.triangles_, mesh.influences_, mesh.bone_labels_);
  mesh.tips_ = findTipVertices (mesh.vertices_, mesh.parts_, mesh.bones_, paths);
  mesh.height_ = standingHeight (mesh.vertices_, paths);
  return mesh;
}

HumanMesh
HumanMesh::load (const std::string &directory, const BodyShape &shape)
{
  const HumanMesh base = load (directory);
  return base.shaped (MakeHumanTargets::load (directory, base.baseVertexCount ()), shape);
}

HumanMesh
HumanMesh::shaped (const MakeHumanTargets &targets, const BodyShape &shape) const
{
  if (targets.vertexCount () != base_vertices_.size ())
    throw HumanMeshError ("the MakeHuman targets are for a mesh of " + std::to_string (targets.vertexCount ()) +
                          " vertices, " + directory_ + "/base.obj has " + std::to_string (base_vertices_.size ()));
  const std::vector<Eigen::Vector3d> offsets = targets.offsets (shape);  // checks the shape
  std::vector<Eigen::Vector3d> all (base_vertices_.size ());
  for (std::size_t v = 0; v < all.size (); ++v)
    all[v] = base_vertices_[v] + offsets[v];

  HumanMesh mesh = *this;
  mesh.shaped_ = true;
  mesh.shape_ = shape;
  for (std::size_t v = 0; v < mesh.vertices_.size (); ++v)
    mesh.vertices_[v] = all[static_cast<std::size_t> (body_vertex_source_[v])];
  // The skeleton follows the shaped mesh: each joint is the mean of its helper vertices,
  // summed in the order the skeleton file lists them (as load does).
  auto mean = [&] (const std::vector<int> &indices) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero ();
    for (const int i : indices)
      sum += all[static_cast<std::size_t> (i)];
    return Eigen::Vector3d (sum / static_cast<double> (indices.size ()));
  };
  for (std::size_t b = 0; b < mesh.bones_.size (); ++b)
  {
    mesh.bones_[b].head = mean (joint_vertices_[2 * b]);
    mesh.bones_[b].tail = mean (joint_vertices_[2 * b + 1]);
  }
  const AssetPaths paths = assetPaths (directory_);
  mesh.tips_ = findTipVertices (mesh.vertices_, mesh.parts_, mesh.bones_, paths);
  mesh.height_ = standingHeight (mesh.vertices_, paths);
  return mesh;
}
}  // namespace agex
