#include <agex/simulation/pose_bank.h>
#include <agex/simulation/pose_retarget.h>
#include <agex/simulation/procedural_poses.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <stdexcept>

namespace agex
{
namespace
{
/** How far below a joint the body's surface reaches (metres), to stand a pose on the floor. */
double
surfaceBelow (int joint)
{
  switch (joint)
  {
    case PoseSkeleton::LeftToeBase:
    case PoseSkeleton::RightToeBase: return 0.025;
    case PoseSkeleton::LeftFoot:
    case PoseSkeleton::RightFoot: return 0.08;
    case PoseSkeleton::Hips: return 0.13;  // sitting on the floor
    case PoseSkeleton::Head: return 0.12;
    case PoseSkeleton::LeftHandIndex1:
    case PoseSkeleton::RightHandIndex1:
    case PoseSkeleton::LeftHand:
    case PoseSkeleton::RightHand: return 0.03;
    default: return 0.06;
  }
}
}  // namespace

int
PoseBank::sourceIndex (const std::string &name)
{
  for (std::size_t i = 0; i < sources_.size (); ++i)
    if (sources_[i].name == name)
      return static_cast<int> (i);
  sources_.push_back ({name, 0, 0, 0});
  return static_cast<int> (sources_.size ()) - 1;
}

void
PoseBank::push (int source, PoseFrame pose)
{
  if (static_cast<int> (poses_.size ()) >= kMaxPoses)
    throw std::length_error ("pose bank: more than " + std::to_string (kMaxPoses) + " poses");
  // Stand the pose on the floor (y = 0) over the origin: the scene places and turns it.
  pose.root.x () = pose.root.z () = 0.0;
  const std::vector<Eigen::Vector3d> p = PoseSkeleton::positions (pose);
  double lowest = std::numeric_limits<double>::infinity ();
  for (int j = 0; j < PoseSkeleton::kJoints; ++j)
    lowest = std::min (lowest, p[j].y () - surfaceBelow (j));
  pose.root.y () -= lowest;
  poses_.push_back (std::move (pose));
  pose_source_.push_back (source);
  ++sources_[static_cast<std::size_t> (source)].raw;
  ++sources_[static_cast<std::size_t> (source)].kept;
}

void
PoseBank::addFile (const std::string &path, const std::string &source_name)
{
  const BvhMotion motion = BvhMotion::read (path);
  if (motion.frameCount () < 1)
    throw BvhError (path + ": the MOTION section has no frames");
  if (static_cast<long> (poses_.size ()) + motion.frameCount () > kMaxPoses)
    throw std::length_error (path + ": the pose bank would hold more than " + std::to_string (kMaxPoses) + " poses");
  const PoseRetarget retarget (motion);
  const int source = sourceIndex (source_name.empty () ? std::filesystem::path (path).stem ().string () : source_name);
  for (int f = 0; f < motion.frameCount (); ++f)
  {
    if (retarget.zeroedLeg (f))
    {
      ++sources_[static_cast<std::size_t> (source)].raw;
      ++sources_[static_cast<std::size_t> (source)].dropped;
      continue;
    }
    PoseFrame pose = retarget.pose (f);
    bool finite = pose.root.allFinite ();
    for (const auto &r : pose.local)
      finite = finite && r.allFinite ();
    if (!finite)
    {
      ++sources_[static_cast<std::size_t> (source)].raw;
      ++sources_[static_cast<std::size_t> (source)].dropped;
      continue;
    }
    push (source, std::move (pose));
  }
}

void
PoseBank::addDirectory (const std::string &directory)
{
  namespace fs = std::filesystem;
  std::error_code error;
  if (!fs::is_directory (directory, error))
    throw BvhError (directory + ": not a directory of BVH files");
  std::vector<std::string> files;
  for (fs::directory_iterator it (directory, error), end; !error && it != end; it.increment (error))
    if (it->path ().extension () == ".bvh" && it->is_regular_file ())
    {
      if (static_cast<int> (files.size ()) >= kMaxFiles)
        throw BvhError (directory + ": more than " + std::to_string (kMaxFiles) + " BVH files");
      files.push_back (it->path ().string ());
    }
  if (error)
    throw BvhError (directory + ": cannot list the directory (" + error.message () + ")");
  if (files.empty ())
    throw BvhError (directory + ": no .bvh files in the directory");
  std::sort (files.begin (), files.end ());
  std::string name = fs::path (directory).filename ().string ();
  if (name.empty ())
    name = fs::path (directory).parent_path ().filename ().string ();
  for (const auto &file : files)
    addFile (file, name);
}

void
PoseBank::addProcedural (int count, std::uint64_t seed)
{
  const std::vector<ProceduralPose> made = ProceduralPoses::generate (count, seed);
  const int source = sourceIndex ("procedural");
  sources_[static_cast<std::size_t> (source)].raw += count - static_cast<int> (made.size ());
  sources_[static_cast<std::size_t> (source)].dropped += count - static_cast<int> (made.size ());
  for (const auto &p : made)
    push (source, p.frame);
}

void
PoseBank::addPoses (const std::string &source_name, const std::vector<PoseFrame> &poses)
{
  const int source = sourceIndex (source_name);
  for (const auto &p : poses)
    push (source, p);
}

std::vector<Eigen::Vector3d>
PoseBank::comparable (const PoseFrame &pose)
{
  std::vector<Eigen::Vector3d> p = PoseSkeleton::positions (pose);
  const Eigen::Matrix3d pelvis = pose.local.empty () ? Eigen::Matrix3d::Identity () : pose.local[0];
  const Eigen::Vector3d left = pelvis.col (0);
  const double yaw = std::atan2 (-left.z (), left.x ());  // the pelvis's turn about Y
  const Eigen::Matrix3d unturn = Eigen::AngleAxisd (-yaw, Eigen::Vector3d::UnitY ()).toRotationMatrix ();
  const Eigen::Vector3d root = p[PoseSkeleton::Hips];
  for (auto &q : p)
    q = unturn * (q - root);
  return p;
}

double
PoseBank::distance (const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b)
{
  double d = 0.0;
  for (std::size_t j = 0; j < std::min (a.size (), b.size ()); ++j)
    d = std::max (d, (a[j] - b[j]).norm ());
  return d;
}

std::vector<int>
PoseBank::furthestPointSample (const std::vector<std::vector<Eigen::Vector3d>> &items, double threshold)
{
  std::vector<int> kept;
  if (items.empty ())
    return kept;
  std::vector<double> nearest (items.size (), std::numeric_limits<double>::infinity ());
  int next = 0;
  for (;;)
  {
    kept.push_back (next);
    nearest[static_cast<std::size_t> (next)] = -1.0;
    int farthest = -1;
    double far = -1.0;
    for (std::size_t i = 0; i < items.size (); ++i)
    {
      if (nearest[i] < 0)
        continue;
      nearest[i] = std::min (nearest[i], distance (items[i], items[static_cast<std::size_t> (next)]));
      if (nearest[i] > far)
      {
        far = nearest[i];
        farthest = static_cast<int> (i);
      }
    }
    if (farthest < 0 || !(far > threshold))
      break;
    next = farthest;
  }
  std::sort (kept.begin (), kept.end ());
  return kept;
}

void
PoseBank::thin (double metres)
{
  if (!(metres >= 0.0) || !std::isfinite (metres))
    throw std::invalid_argument ("pose bank: the thinning distance must be >= 0 metres, got " + std::to_string (metres));
  if (metres == 0.0 || poses_.empty ())
    return;
  std::vector<std::vector<Eigen::Vector3d>> items;
  items.reserve (poses_.size ());
  for (const auto &p : poses_)
    items.push_back (comparable (p));
  const std::vector<int> kept = furthestPointSample (items, metres);
  std::vector<PoseFrame> poses;
  std::vector<int> sources;
  for (auto &s : sources_)
    s.kept = 0;
  for (const int i : kept)
  {
    poses.push_back (poses_[static_cast<std::size_t> (i)]);
    sources.push_back (pose_source_[static_cast<std::size_t> (i)]);
    ++sources_[static_cast<std::size_t> (sources.back ())].kept;
  }
  poses_ = std::move (poses);
  pose_source_ = std::move (sources);
}

PoseBank
poseBankOf (const SynthOptions &options)
{
  PoseBank bank;
  for (const auto &path : options.motion_files)
    bank.addFile (path);
  for (const auto &dir : options.pose_dirs)
    bank.addDirectory (dir);
  if (options.procedural_poses > 0)
    bank.addProcedural (options.procedural_poses, options.seed);
  if (bank.size () == 0)
    throw std::invalid_argument ("the pose bank has no poses (every frame of its files was dropped)");
  bank.thin (options.thin_poses);
  return bank;
}

MotionClip
PoseBank::clip (const std::string &name) const
{
  MotionClip clip;
  clip.motion = PoseSkeleton::motion (poses_, name);
  clip.map = SkeletonMap::find (clip.motion);
  clip.scale = 1.0;
  clip.scale_auto = false;
  clip.sequence = name;
  return clip;
}

std::vector<HandSpread>
PoseBank::handSpread () const
{
  std::vector<HandSpread> out (sources_.size () + 1);
  for (std::size_t s = 0; s < sources_.size (); ++s)
    out[s].source = sources_[s].name;
  out.back ().source = "all";
  std::vector<Eigen::Vector3d> sum (out.size (), Eigen::Vector3d::Zero ()), sum2 (out.size (), Eigen::Vector3d::Zero ());
  for (std::size_t i = 0; i < poses_.size (); ++i)
  {
    const std::vector<Eigen::Vector3d> p = comparable (poses_[i]);
    const double head_top = p[PoseSkeleton::Head].y ();
    for (int side = 0; side < 2; ++side)
    {
      const Eigen::Vector3d w = p[side == 0 ? PoseSkeleton::LeftHand : PoseSkeleton::RightHand];
      const Eigen::Vector3d h (side == 0 ? w.x () : -w.x (), w.y (), w.z ());
      for (const std::size_t k : {static_cast<std::size_t> (pose_source_[i]), out.size () - 1})
      {
        HandSpread &s = out[k];
        ++s.hands;
        sum[k] += h;
        sum2[k] += h.cwiseProduct (h);
        s.above_head += h.y () > head_top;
        s.forward += h.z () > 0.35;
        s.behind += h.z () < -0.10;
        s.across += h.x () < 0.0;
      }
    }
  }
  for (std::size_t k = 0; k < out.size (); ++k)
  {
    HandSpread &s = out[k];
    if (s.hands == 0)
      continue;
    const double n = s.hands;
    s.mean = sum[k] / n;
    s.sd = (sum2[k] / n - s.mean.cwiseProduct (s.mean)).cwiseMax (0.0).cwiseSqrt ();
    s.above_head /= n;
    s.forward /= n;
    s.behind /= n;
    s.across /= n;
  }
  return out;
}

cv::Mat
PoseBank::spreadImage () const
{
  // Two panels, front (x, y) and top (x, z), 2.4 m across each, the legend below.
  const int panel = 440, ppm = 180;
  cv::Mat image (panel + 60, 2 * panel, CV_8UC3, cv::Scalar (255, 255, 255));
  const cv::Scalar colours[] = {{200, 80, 30}, {40, 140, 40}, {30, 60, 220}, {160, 60, 160}, {20, 160, 200}, {90, 90, 90}};
  auto front = [&] (const Eigen::Vector3d &p) {
    return cv::Point (panel / 2 + static_cast<int> (p.x () * ppm), 30 + panel / 2 - static_cast<int> (p.y () * ppm));
  };
  auto top = [&] (const Eigen::Vector3d &p) {
    return cv::Point (panel + panel / 2 + static_cast<int> (p.x () * ppm), 30 + panel / 2 - static_cast<int> (p.z () * ppm));
  };
  // Hands first, a source after the other, the skeleton over them.
  for (std::size_t i = 0; i < poses_.size (); ++i)
  {
    const std::vector<Eigen::Vector3d> p = comparable (poses_[i]);
    const cv::Scalar &colour = colours[static_cast<std::size_t> (pose_source_[i]) % 6];
    for (const int j : {static_cast<int> (PoseSkeleton::LeftHand), static_cast<int> (PoseSkeleton::RightHand)})
    {
      cv::circle (image, front (p[j]), 1, colour, cv::FILLED);
      cv::circle (image, top (p[j]), 1, colour, cv::FILLED);
    }
  }
  PoseFrame rest;
  rest.local.assign (PoseSkeleton::kJoints, Eigen::Matrix3d::Identity ());
  const std::vector<Eigen::Vector3d> r = comparable (rest);
  for (int j = 1; j < PoseSkeleton::kJoints; ++j)
  {
    const int par = PoseSkeleton::parent (j);
    cv::line (image, front (r[par]), front (r[j]), cv::Scalar (0, 0, 0), 2);
    cv::line (image, top (r[par]), top (r[j]), cv::Scalar (0, 0, 0), 2);
  }
  cv::line (image, cv::Point (panel, 30), cv::Point (panel, panel + 30), cv::Scalar (0, 0, 0), 1);
  cv::putText (image, "front (x out, y up)", cv::Point (8, 22), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar (0, 0, 0), 1);
  cv::putText (image, "top (x out, z forward)", cv::Point (panel + 8, 22), cv::FONT_HERSHEY_SIMPLEX, 0.5,
               cv::Scalar (0, 0, 0), 1);
  int x = 8;
  for (std::size_t s = 0; s < sources_.size () && x < 2 * panel - 40; ++s)
  {
    cv::putText (image, sources_[s].name, cv::Point (x, panel + 50), cv::FONT_HERSHEY_SIMPLEX, 0.5, colours[s % 6], 1);
    x += 16 + 10 * static_cast<int> (sources_[s].name.size ());
  }
  return image;
}
}  // namespace agex
