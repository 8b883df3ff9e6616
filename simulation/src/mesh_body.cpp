// The MakeHuman mesh posed by a motion capture clip (linear blend skinning).
#include <agex/simulation/human_mesh.h>
#include <agex/simulation/synthetic_scene.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <limits>
#include <unordered_map>

namespace agex
{
namespace
{
/** What moves a bone: a motion capture segment (index 0 = left side). */
enum Driver : int
{
  Root,
  SpineBase,
  Chest,
  Neck,
  HeadSegment,
  UpperArm,             // + side
  ForeArm = UpperArm + 2,
  Hand = ForeArm + 2,
  Thigh = Hand + 2,
  Shin = Thigh + 2,
  Foot = Shin + 2,
  kDrivers = Foot + 2
};

/** How girth parameters shape a bone's vertices. */
enum class Shaping
{
  Torso,
  Arm,
  Leg,
  Extremity,
  Head
};

Shaping
shapingOf (int driver)
{
  if (driver <= Neck)
    return Shaping::Torso;
  if (driver == HeadSegment)
    return Shaping::Head;
  if (driver < Hand)
    return Shaping::Arm;
  if (driver < Thigh)
    return Shaping::Extremity;
  if (driver < Foot)
    return Shaping::Leg;
  return Shaping::Extremity;
}

/** Each bone's driver: from its name, else its parent's (parents come first). */
std::vector<int>
boneDrivers (const HumanMesh &mesh)
{
  static const std::unordered_map<std::string, int> named = {
      {"root", Root},           {"spine03", SpineBase},         {"spine02", Chest},
      {"neck01", Neck},         {"head", HeadSegment},          {"upperarm01.L", UpperArm},
      {"upperarm01.R", UpperArm + 1}, {"lowerarm01.L", ForeArm}, {"lowerarm01.R", ForeArm + 1},
      {"wrist.L", Hand},        {"wrist.R", Hand + 1},          {"upperleg01.L", Thigh},
      {"upperleg01.R", Thigh + 1}, {"lowerleg01.L", Shin},      {"lowerleg01.R", Shin + 1},
      {"foot.L", Foot},         {"foot.R", Foot + 1}};
  std::vector<int> drivers (mesh.bones ().size (), Root);
  for (std::size_t b = 0; b < mesh.bones ().size (); ++b)
  {
    const auto found = named.find (mesh.bones ()[b].name);
    const int parent = mesh.bones ()[b].parent;
    drivers[b] = found != named.end () ? found->second : parent >= 0 ? drivers[static_cast<std::size_t> (parent)] : Root;
  }
  return drivers;
}

/** The mesh's bones posed on one clip frame, in the clip's world frame (metres). */
class MeshPose
{
public:
  MeshPose (const MotionClip &clip, int frame, const BodyParams &params, const HumanMesh &mesh)
    : mesh_ (mesh), params_ (params), drivers_ (boneDrivers (mesh)),
      head_pivot_ (mesh.bones ()[static_cast<std::size_t> (mesh.bone ("head"))].head)
  {
    const SkeletonMap &m = clip.map;
    // Rest mesh -> world: MakeHuman's (left, up, forward) onto the clip's, scaled to the
    // clip's rest height.
    to_world_ = m.rest_basis * (restStandingHeight (clip) * params.height_scale / mesh.height ());
    std::vector<Eigen::Isometry3d> g, g0;
    clip.motion.pose (frame, clip.scale * params.height_scale, g);
    clip.motion.pose (-1, clip.scale * params.height_scale, g0);
    auto P = [&] (int j) -> Eigen::Vector3d { return g[static_cast<std::size_t> (j)].translation (); };
    auto Q = [&] (int j) -> Eigen::Matrix3d {
      return g[static_cast<std::size_t> (j)].linear () * g0[static_cast<std::size_t> (j)].linear ().transpose ();
    };
    auto head_of = [&] (const std::string &bone) -> Eigen::Vector3d {
      return mesh.bones ()[static_cast<std::size_t> (mesh.bone (bone))].head;
    };
    // Rotation of joint j, then turned so the rest segment from bone a's head to bone
    // b's head points along `target`.
    auto follow = [&] (int j, const Eigen::Vector3d &rest_from, const Eigen::Vector3d &rest_to,
                       const Eigen::Vector3d &target) -> Eigen::Matrix3d {
      const Eigen::Matrix3d q = Q (j);
      const Eigen::Vector3d now = q * (m.rest_basis * (rest_to - rest_from));
      if (target.norm () < 1e-9 || now.norm () < 1e-12)
        return q;
      return Eigen::Quaterniond::FromTwoVectors (now, target).toRotationMatrix () * q;
    };
    Eigen::Matrix3d driver[kDrivers];
    driver[Root] = Q (m.root);
    driver[SpineBase] = Q (m.spine_base);
    driver[Chest] = Q (m.spine_mid);
    driver[Neck] = follow (m.neck, head_of ("neck01"), head_of ("head"), P (m.head) - P (m.neck));
    {
      const auto &head = mesh.bones ()[static_cast<std::size_t> (mesh.bone ("head"))];
      driver[HeadSegment] = m.head_end >= 0 ? follow (m.head, head.head, head.tail, P (m.head_end) - P (m.head)) : Q (m.head);
    }
    for (int side = 0; side < 2; ++side)
    {
      const std::string s = side == 0 ? ".L" : ".R";
      driver[UpperArm + side] = follow (m.shoulder[side], head_of ("upperarm01" + s), head_of ("lowerarm01" + s),
                                        P (m.elbow[side]) - P (m.shoulder[side]));
      driver[ForeArm + side] = follow (m.elbow[side], head_of ("lowerarm01" + s), head_of ("wrist" + s),
                                       P (m.wrist[side]) - P (m.elbow[side]));
      Eigen::Vector3d hand_dir = P (m.wrist[side]) - P (m.elbow[side]);
      if (m.hand_end[side] >= 0 && (P (m.hand_end[side]) - P (m.wrist[side])).norm () > 0.01 * params.height_scale)
        hand_dir = P (m.hand_end[side]) - P (m.wrist[side]);
      driver[Hand + side] = follow (m.wrist[side], head_of ("wrist" + s), head_of ("finger3-1" + s), hand_dir);
      driver[Thigh + side] = follow (m.hip[side], head_of ("upperleg01" + s), head_of ("lowerleg01" + s),
                                     P (m.knee[side]) - P (m.hip[side]));
      driver[Shin + side] = follow (m.knee[side], head_of ("lowerleg01" + s), head_of ("foot" + s),
                                    P (m.ankle[side]) - P (m.knee[side]));
      driver[Foot + side] = m.toe[side] >= 0 ? follow (m.ankle[side], head_of ("foot" + s), head_of ("toe3-1" + s),
                                                       P (m.toe[side]) - P (m.ankle[side]))
                                             : Q (m.ankle[side]);
    }

    // Bone heads: the root is placed so the mesh's hip centre lands on the clip's root
    // joint; every other head hangs off its parent.
    const std::size_t n = mesh.bones ().size ();
    rotation_.resize (n);
    rest_head_.resize (n);
    posed_head_.resize (n);
    const Eigen::Vector3d hips = to_world_ * (0.5 * (head_of ("upperleg01.L") + head_of ("upperleg01.R")));
    for (std::size_t b = 0; b < n; ++b)
    {
      const auto &bone = mesh.bones ()[b];
      rotation_[b] = driver[drivers_[b]];
      rest_head_[b] = to_world_ * bone.head;
      if (bone.parent < 0)
        posed_head_[b] = P (m.root) + rotation_[b] * (rest_head_[b] - hips);
      else
      {
        const auto p = static_cast<std::size_t> (bone.parent);
        posed_head_[b] = posed_head_[p] + rotation_[p] * (rest_head_[b] - rest_head_[p]);
      }
    }
  }

  /** Vertex v of the mesh, shaped by the body parameters and posed. */
  Eigen::Vector3d vertex (std::size_t v) const
  {
    const Eigen::Vector3d rest = mesh_.vertices ()[v];
    Eigen::Vector3d posed = Eigen::Vector3d::Zero ();
    for (const auto &influence : mesh_.influences ()[v])
    {
      const auto b = static_cast<std::size_t> (influence.bone);
      const Eigen::Vector3d shaped = to_world_ * shape (rest, b);
      posed += influence.weight * (rotation_[b] * (shaped - rest_head_[b]) + posed_head_[b]);
    }
    return posed;
  }

  const Eigen::Vector3d &posedHead (const std::string &bone) const
  {
    return posed_head_[static_cast<std::size_t> (mesh_.bone (bone))];
  }
  const std::vector<Eigen::Vector3d> &posedHeads () const { return posed_head_; }

private:
  /** A rest vertex as bone b's girth parameters shape it (MakeHuman frame): the offset
    * from the bone's axis is scaled, the head about the top of the neck. */
  Eigen::Vector3d shape (const Eigen::Vector3d &v, std::size_t b) const
  {
    const auto &bone = mesh_.bones ()[b];
    const Shaping how = shapingOf (drivers_[b]);
    if (how == Shaping::Head)  // face bones too: the whole head about the top of the neck
      return head_pivot_ + params_.head_scale * (v - head_pivot_);
    const Eigen::Vector3d axis = bone.tail - bone.head;
    const double len2 = axis.squaredNorm ();
    const Eigen::Vector3d on_axis = len2 > 1e-12 ? Eigen::Vector3d (bone.head + axis * ((v - bone.head).dot (axis) / len2))
                                                 : bone.head;
    Eigen::Vector3d offset = v - on_axis;
    switch (how)
    {
      case Shaping::Torso:
        offset.x () *= params_.girth;
        offset.z () *= params_.girth * params_.torso_depth;
        break;
      case Shaping::Arm: offset *= params_.girth * params_.arm_girth; break;
      case Shaping::Leg: offset *= params_.girth * params_.leg_girth; break;
      case Shaping::Extremity: offset *= 0.5 + 0.5 * params_.girth; break;
      case Shaping::Head: break;
    }
    return on_axis + offset;
  }

  const HumanMesh &mesh_;
  const BodyParams &params_;
  std::vector<int> drivers_;
  Eigen::Vector3d head_pivot_;
  Eigen::Matrix3d to_world_;
  std::vector<Eigen::Matrix3d> rotation_;
  std::vector<Eigen::Vector3d> rest_head_, posed_head_;
};

/** The parameters a mesh is posed with. A shaped mesh (HumanMesh::shaped) has its
  * MakeHuman stature and girth: the sizes of BodyParams are ignored (reflectivity is
  * kept) and the clip's motion is scaled to the mesh's height (height_scale = mesh
  * height / the clip's rest height), so the body is posed at its true size and the
  * root travels in proportion to it. An unshaped mesh is scaled to the clip's rest
  * height times height_scale and widened by the girth parameters, as before. */
BodyParams
meshParams (const MotionClip &clip, const BodyParams &params, const HumanMesh &mesh)
{
  if (!mesh.isShaped ())
    return params;
  BodyParams shaped;
  shaped.reflectivity = params.reflectivity;
  shaped.clothes_top = params.clothes_top;
  shaped.clothes_bottom = params.clothes_bottom;
  shaped.shoes = params.shoes;
  shaped.hands = params.hands;
  shaped.hair = params.hair;
  shaped.height_scale = mesh.height () / restStandingHeight (clip);
  return shaped;
}

/** Clothes: how far each vertex moves out (BodyParams::clothes_top ...), by its part;
  * hair is full on the top of the head (the rest pose's head top) and none below its
  * middle. Empty for a bare body. */
std::vector<double>
clothesOffsets (const HumanMesh &mesh, const BodyParams &params)
{
  if (!params.dressed ())
    return {};
  const std::size_t n = mesh.vertices ().size ();
  double head_low = std::numeric_limits<double>::infinity ();
  const int top = mesh.tipVertices ()[HumanMesh::Head];
  const double head_top = top >= 0 ? mesh.vertices ()[static_cast<std::size_t> (top)].y () : 0.0;
  for (std::size_t v = 0; v < n; ++v)
    if (mesh.parts ()[v] == HumanMesh::Head)
      head_low = std::min (head_low, mesh.vertices ()[v].y ());
  const double head_middle = 0.5 * (head_low + head_top);
  std::vector<double> offsets (n, 0.0);
  for (std::size_t v = 0; v < n; ++v)
  {
    switch (mesh.parts ()[v])
    {
    case HumanMesh::Trunk:
    case HumanMesh::LeftArm:
    case HumanMesh::RightArm:
      offsets[v] = params.clothes_top;
      break;
    case HumanMesh::LeftLeg:
    case HumanMesh::RightLeg:
      offsets[v] = params.clothes_bottom;
      break;
    case HumanMesh::LeftFoot:
    case HumanMesh::RightFoot:
      offsets[v] = params.shoes;
      break;
    case HumanMesh::LeftHand:
    case HumanMesh::RightHand:
      offsets[v] = params.hands;
      break;
    case HumanMesh::Head:
      if (top >= 0 && head_top > head_middle)
        offsets[v] = params.hair * std::clamp ((mesh.vertices ()[v].y () - head_middle) / (head_top - head_middle), 0.0, 1.0);
      break;
    default:
      break;
    }
  }
  return offsets;
}

/** Dresses a posed body: each vertex moved out along its normal (the posed triangles'
  * area-weighted sum, turned outward if the mesh winds the other way) by its offset; one
  * offset per vertex, so parts that share a seam stay joined. */
void
dressVertices (std::vector<Eigen::Vector3d> &posed, const HumanMesh &mesh, const BodyParams &params)
{
  const std::vector<double> offsets = clothesOffsets (mesh, params);
  if (offsets.empty ())
    return;
  std::vector<Eigen::Vector3d> normals (posed.size (), Eigen::Vector3d::Zero ());
  for (const auto &t : mesh.triangles ())
  {
    const auto a = static_cast<std::size_t> (t[0]), b = static_cast<std::size_t> (t[1]),
               c = static_cast<std::size_t> (t[2]);
    const Eigen::Vector3d n = (posed[b] - posed[a]).cross (posed[c] - posed[a]);
    for (int k = 0; k < 3; ++k)
      normals[static_cast<std::size_t> (t[k])] += n;
  }
  Eigen::Vector3d centre = Eigen::Vector3d::Zero ();
  for (const auto &p : posed)
    centre += p;
  centre /= static_cast<double> (std::max<std::size_t> (posed.size (), 1));
  double outward = 0.0;
  for (std::size_t v = 0; v < posed.size (); ++v)
    outward += normals[v].dot (posed[v] - centre);
  const double sign = outward < 0.0 ? -1.0 : 1.0;
  for (std::size_t v = 0; v < posed.size (); ++v)
  {
    const double length = normals[v].norm ();
    if (offsets[v] > 0.0 && length > 0.0)
      posed[v] += (sign * offsets[v] / length) * normals[v];
  }
}

SynthMaterial
partMaterial (HumanMesh::Part part)
{
  switch (part)
  {
  case HumanMesh::Head:
  case HumanMesh::LeftHand:
  case HumanMesh::RightHand:
    return SynthMaterial::Skin;
  case HumanMesh::LeftFoot:
  case HumanMesh::RightFoot:
    return SynthMaterial::Shoes;
  case HumanMesh::LeftLeg:
  case HumanMesh::RightLeg:
    return SynthMaterial::Bottom;
  default:
    return SynthMaterial::Top;
  }
}
}  // namespace

BodyModel
buildMeshBody (const MotionClip &clip, int frame, const BodyParams &given, const HumanMesh &mesh)
{
  const BodyParams params = meshParams (clip, given, mesh);
  const MeshPose pose (clip, frame, params, mesh);
  const std::size_t n = mesh.vertices ().size ();
  std::vector<Eigen::Vector3d> posed (n);
  for (std::size_t v = 0; v < n; ++v)
    posed[v] = pose.vertex (v);
  dressVertices (posed, mesh, params);

  BodyModel body;
  // One mesh per part, so a label's visibility test can ask which part a ray hit, the
  // renderer sees limb edges in front of the torso as edges between primitives, and
  // the room is kept clear of each part's own bounding sphere.
  for (int part = 0; part < HumanMesh::kParts; ++part)
  {
    std::vector<int> local (n, -1);
    std::vector<Eigen::Vector3d> vertices;
    std::vector<Eigen::Vector3i> triangles;
    auto labels = std::make_shared<std::vector<SynthPart>> ();
    for (std::size_t t = 0; t < mesh.triangles ().size (); ++t)
    {
      if (mesh.triangleParts ()[t] != part)
        continue;
      labels->push_back (mesh.triangleLabels ()[t]);
      Eigen::Vector3i corners;
      for (int k = 0; k < 3; ++k)
      {
        const auto v = static_cast<std::size_t> (mesh.triangles ()[t][k]);
        if (local[v] < 0)
        {
          local[v] = static_cast<int> (vertices.size ());
          vertices.push_back (posed[v]);
        }
        corners[k] = local[v];
      }
      triangles.push_back (corners);
    }
    SynthPrimitive primitive = SynthPrimitive::triangleMesh (
        std::make_shared<const SynthMesh> (std::move (vertices), std::move (triangles)), SynthObject::Person);
    primitive.reflectivity = static_cast<float> (params.reflectivity);
    primitive.material = partMaterial (static_cast<HumanMesh::Part> (part));
    // Pixel labels per triangle, finer than the primitives (an arm is upper arm and forearm).
    primitive.triangle_parts = std::move (labels);
    body.primitives.push_back (std::move (primitive));
  }

  // Tips are vertices; tolerances as for the capsule body (the part's radius + 3 cm).
  const double s = params.height_scale;
  const HumanMesh::Part parts[5] = {HumanMesh::Head, HumanMesh::LeftHand, HumanMesh::RightHand, HumanMesh::LeftFoot,
                                    HumanMesh::RightFoot};
  const char *bases[5] = {"head", "wrist.L", "wrist.R", "foot.L", "foot.R"};
  const double extremity = 0.5 + 0.5 * params.girth;
  // A dressed tip stands its part's thickness farther out.
  const double clothes[5] = {params.hair, params.hands, params.hands, params.shoes, params.shoes};
  const double radius[5] = {0.095 * s * params.head_scale, 0.03 * s * extremity, 0.03 * s * extremity,
                            0.04 * s * extremity, 0.04 * s * extremity};
  for (int i = 0; i < 5; ++i)
  {
    body.tip[i] = posed[static_cast<std::size_t> (mesh.tipVertices ()[parts[i]])];
    body.base[i] = pose.posedHead (bases[i]);
    body.tip_primitives[i] = {static_cast<int> (parts[i])};
    body.tip_tolerance[i] = radius[i] + 0.03 + clothes[i];
  }
  body.centre = 0.5 * (pose.posedHead ("root") + pose.posedHead ("neck01"));
  body.lowest = std::numeric_limits<double>::infinity ();
  body.highest = -body.lowest;
  for (const auto &p : posed)
  {
    body.lowest = std::min (body.lowest, p.y ());
    body.highest = std::max (body.highest, p.y ());
  }
  return body;
}

std::vector<Eigen::Vector3d>
meshBoneHeads (const MotionClip &clip, int frame, const BodyParams &params, const HumanMesh &mesh)
{
  const BodyParams posed_with = meshParams (clip, params, mesh);
  return MeshPose (clip, frame, posed_with, mesh).posedHeads ();
}

double
meshBodyLowest (const MotionClip &clip, int frame, const BodyParams &given, const HumanMesh &mesh)
{
  const BodyParams params = meshParams (clip, given, mesh);
  const MeshPose pose (clip, frame, params, mesh);
  double lowest = std::numeric_limits<double>::infinity ();
  // Clothes: at the lowest point the outward normal points down, so a dressed vertex
  // there lies its offset lower (to first order; exact for a sole flat on the floor).
  const std::vector<double> offsets = clothesOffsets (mesh, params);
  for (std::size_t v = 0; v < mesh.vertices ().size (); ++v)
  {
    const HumanMesh::Part part = mesh.parts ()[v];
    if (part == HumanMesh::LeftFoot || part == HumanMesh::RightFoot || v % 16 == 0)
      lowest = std::min (lowest, pose.vertex (v).y () - (offsets.empty () ? 0.0 : offsets[v]));
  }
  return lowest;
}
}  // namespace agex
