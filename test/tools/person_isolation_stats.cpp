// person_isolation_stats: how agex::PersonSegmentation does on real frames moved away from the
// camera (doc/pipeline.md, "People"). A developer's measuring tool, built with the tests.
//   person_isolation_stats bonn SHARED_DATA [SEQUENCES [SHIFTS]] [--pipeline]
//       Bonn keyframes of SEQUENCES (default "7,8"; "5_025" is one keyframe), every finite point moved by (dx, 0, dz)
//       for each "dz:dx" of SHIFTS (default "0:0,1:0,1.5:0,2:0,1:-0.6,1:0.6,2:-0.6,2:0.6"),
//       re-projected with the Kinect intrinsics the data documents (fx = fy = 525,
//       cx = 319.5, cy = 239.5) and z-buffered into a frame of the same size (each point
//       splatted over the pixels its own pixel covers there, nearest depth wins). Per shift and
//       view (640x480 and the 144x176 portrait view): frames with the person found, person
//       pixels against the native count scaled by (z0 / z1)^2 and against the native person's
//       pixels carried along, precision, other persons found, and the labelled head, hand and
//       foot tips with a person pixel within 5 cm. --pipeline adds the foot tips left after
//       each stage of agex::DepthPipeline (640x480). --dump PREFIX KEYFRAME (e.g. 7_022)
//       writes PREFIX_dz_dx_view.png of that keyframe: depth in grey, persons red, their
//       pixels under 4 cm blue, the native person's pixels no one took green; --crop
//       x,y,w,h,zoom shows a part of it enlarged.
//   person_isolation_stats bonn-all SHARED_DATA
//       All Bonn frames at 640x480 and 144x176: frames with exactly one person, the person's
//       meshes against the crop box's (IoU), keyframe tips within 3 (1) pixels of the person.
//   person_isolation_stats dataset DIR
//       A synthetic dataset with person images (agex_synth --people N): labelled persons with
//       a visible tip at 0.8-4 m isolated, found persons mostly no one (doc/results.md).
//   person_isolation_stats kinect SHARED_DATA
//       five_people.pcd and Skeltrack's frames: persons, their columns, depths and pixels.
#include <agex/detection/depth_pipeline.h>
#include <agex/filters/person_segmentation.h>
#include <agex/io/atomic_file.h>
#include <agex/io/bonn.h>
#include <agex/io/frame_io.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace
{
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

std::vector<std::string>
splitList (const std::string &text)
{
  std::vector<std::string> out;
  std::stringstream s (text);
  std::string item;
  while (std::getline (s, item, ','))
    if (!item.empty ())
      out.push_back (item);
  return out;
}

Cloud::Ptr
nanCloud (int width, int height)
{
  Cloud::Ptr c (new Cloud);
  const float nan = std::numeric_limits<float>::quiet_NaN ();
  c->points.assign (static_cast<std::size_t> (width) * height, pcl::PointXYZ (nan, nan, nan));
  c->width = width;
  c->height = height;
  c->is_dense = false;
  return c;
}

/** Every finite point moved by (dx, 0, dz), projected with K and z-buffered; tag carried along. */
void
moveFrame (const Cloud &in, const std::vector<unsigned char> &tag, float dx, float dz, const agex::CameraIntrinsics &K,
           Cloud::Ptr &out, std::vector<unsigned char> &out_tag)
{
  const int w = static_cast<int> (in.width), h = static_cast<int> (in.height);
  out = nanCloud (w, h);
  out_tag.assign (in.size (), 0);
  std::vector<float> zbuf (in.size (), std::numeric_limits<float>::infinity ());
  for (std::size_t i = 0; i < in.size (); ++i)
  {
    const pcl::PointXYZ &p = in[i];
    if (!std::isfinite (p.z))
      continue;
    const float x = p.x + dx, y = p.y, z = p.z + dz;
    if (!(z > 0.1f))
      continue;
    const double u = K.fx * x / z + K.cx, v = K.fy * y / z + K.cy;
    // The source pixel's footprint at the new depth (at least one pixel).
    const int s = std::max (1, std::min (4, static_cast<int> (std::ceil (p.z / z - 1e-3))));
    const int u0 = static_cast<int> (std::lround (u - 0.5 * (s - 1))), v0 = static_cast<int> (std::lround (v - 0.5 * (s - 1)));
    for (int tv = v0; tv < v0 + s; ++tv)
      for (int tu = u0; tu < u0 + s; ++tu)
      {
        if (tu < 0 || tu >= w || tv < 0 || tv >= h)
          continue;
        const int j = tv * w + tu;
        if (z >= zbuf[j])
          continue;
        zbuf[j] = z;
        (*out)[j] = pcl::PointXYZ (static_cast<float> ((tu - K.cx) * z / K.fx), static_cast<float> ((tv - K.cy) * z / K.fy), z);
        out_tag[j] = tag[i];
      }
  }
}

/** Whether a pixel with mask set lies within radius metres of point (searched around its projection). */
bool
nearMasked (const Cloud &cloud, const std::vector<unsigned char> &mask, const Eigen::Vector3f &point,
            const agex::CameraIntrinsics &K, float radius)
{
  if (!(point.z () > 0.1f))
    return false;
  const int w = static_cast<int> (cloud.width), h = static_cast<int> (cloud.height);
  const int u = static_cast<int> (std::lround (K.fx * point.x () / point.z () + K.cx));
  const int v = static_cast<int> (std::lround (K.fy * point.y () / point.z () + K.cy));
  const int r = static_cast<int> (std::ceil (radius * K.fx / point.z ())) + 2;
  for (int y = std::max (0, v - r); y <= std::min (h - 1, v + r); ++y)
    for (int x = std::max (0, u - r); x <= std::min (w - 1, u + r); ++x)
    {
      const int j = y * w + x;
      if (mask[j] && std::isfinite (cloud[j].z) && (cloud[j].getVector3fMap () - point).norm () <= radius)
        return true;
    }
  return false;
}

struct Tip
{
  agex::BodyPart part;
  Eigen::Vector3f point;
};

/** Sums over the frames of one shift and view. */
struct Tally
{
  int frames = 0, found = 0, extra = 0;
  long low = 0;
  double ratio_scaled = 0, ratio_carried = 0, precision = 0;
  int matched = 0;
  double worst = 1e9;  ///< smallest pixels/carried of a frame
  std::string worst_frame;
  std::map<agex::BodyPart, std::pair<int, int>> tips;  ///< (with a person pixel, all)
  std::map<std::string, std::pair<int, int>> stage_feet;  ///< pipeline stage -> (kept, all)
};

struct Result
{
  int persons = 0;
  std::vector<unsigned char> person;  ///< any person
  std::vector<unsigned char> best;    ///< the person overlapping the carried mask most
  int best_count = 0, best_overlap = 0;
  int low = 0;  ///< person pixels less than 4 cm above the floor (the feet's lowest, or floor)
  Eigen::Vector4f plane = Eigen::Vector4f::Zero ();
};

Result
isolate (const Cloud::Ptr &cloud, const std::vector<unsigned char> &carried)
{
  agex::PersonSegmentation<pcl::PointXYZ> seg;
  seg.setInputCloud (cloud);
  std::vector<pcl::PointIndices> persons;
  seg.segment (persons);
  Result r;
  r.persons = static_cast<int> (persons.size ());
  r.person.assign (cloud->size (), 0);
  r.best.assign (cloud->size (), 0);
  int best = -1;
  for (int k = 0; k < r.persons; ++k)
  {
    int overlap = 0;
    for (const auto i : persons[k].indices)
    {
      r.person[i] = 1;
      overlap += carried[i];
    }
    if (overlap > r.best_overlap)
    {
      r.best_overlap = overlap;
      best = k;
    }
  }
  if (seg.getFloorFound ())
  {
    const Eigen::Vector4f plane = r.plane = seg.getFloorPlane ();
    for (std::size_t i = 0; i < cloud->size (); ++i)
      r.low += r.person[i] && plane.head<3> ().dot ((*cloud)[i].getVector3fMap ()) + plane[3] < 0.04f;
  }
  if (best >= 0)
  {
    for (const auto i : persons[best].indices)
      r.best[i] = 1;
    r.best_count = static_cast<int> (persons[best].indices.size ());
  }
  return r;
}

/** --dump PREFIX KEYFRAME [--crop x,y,w,h,zoom]: pictures of one keyframe, moved. */
struct Dump
{
  std::string prefix, keyframe;
  cv::Rect crop;
  int zoom = 0;  ///< 0: the whole frame
};

const char *
partName (agex::BodyPart p)
{
  return p == agex::BodyPart::Head ? "head" : p == agex::BodyPart::Hand ? "hand" : "foot";
}

int
runBonn (const std::string &shared, const std::vector<std::string> &sequences, const std::vector<std::string> &shifts,
         bool pipeline, const Dump &dump)
{
  const std::vector<agex::BonnLabel> labels = agex::readBonnLabels (shared + "/bonn/labels.csv");
  std::vector<std::pair<std::string, std::string>> keyframes;
  for (const auto &l : labels)
    if (l.keyframe &&
        (std::find (sequences.begin (), sequences.end (), l.sequence) != sequences.end () ||
         std::find (sequences.begin (), sequences.end (), l.sequence + "_" + l.frame) != sequences.end ()) &&
        std::find (keyframes.begin (), keyframes.end (), std::make_pair (l.sequence, l.frame)) == keyframes.end ())
      keyframes.emplace_back (l.sequence, l.frame);
  const agex::CameraIntrinsics K;  // the data's documented Kinect intrinsics
  const agex::FrameView view = agex::bonnPortraitView ();
  const agex::CameraIntrinsics Kp = view.intrinsics (K);
  std::vector<std::pair<float, float>> moves;
  for (const auto &s : shifts)
  {
    const auto colon = s.find (':');
    moves.emplace_back (std::stof (s.substr (0, colon)), colon == std::string::npos ? 0.f : std::stof (s.substr (colon + 1)));
  }
  std::map<std::pair<std::size_t, int>, Tally> tallies;  // (shift, view 0 full / 1 portrait)
  for (const auto &kf : keyframes)
  {
    const agex::Frame frame = agex::loadFrame (shared + "/bonn/depth/" + kf.first + "/" + kf.second + ".png");
    const Cloud::Ptr native = frame.cloud;
    std::vector<Tip> tips;
    for (const auto &l : labels)
    {
      if (l.sequence != kf.first || l.frame != kf.second)
        continue;
      Eigen::Vector3f p;
      if (agex::liftPixelToSurface (*native, l.tip_px.x (), l.tip_px.y (), 6, 0.05f, p))
        tips.push_back ({l.part, p});
    }
    const std::vector<unsigned char> all (native->size (), 1);
    const Result base = isolate (native, all);
    // The native person: the largest found (Bonn shows one), its median depth.
    std::vector<unsigned char> native_person = base.best;
    std::vector<float> depths;
    for (std::size_t i = 0; i < native->size (); ++i)
      if (native_person[i])
        depths.push_back ((*native)[i].z);
    if (depths.empty ())
    {
      std::cout << kf.first << "_" << kf.second << ": no person at the native distance\n";
      continue;
    }
    std::nth_element (depths.begin (), depths.begin () + depths.size () / 2, depths.end ());
    const float z0 = depths[depths.size () / 2];
    // Native counts per view (portrait: the view of the native frame).
    Cloud native_portrait;
    agex::applyView (*native, view, native_portrait);
    int native_full = base.best_count, native_view = 0;
    {
      Cloud::Ptr np (new Cloud (native_portrait));
      std::vector<unsigned char> carried (np->size (), 0);
      for (int v = 0; v < view.outputHeight (); ++v)
        for (int u = 0; u < view.outputWidth (); ++u)
        {
          const cv::Point s = view.sourcePixel (u, v);
          carried[v * view.outputWidth () + u] = native_person[s.y * native->width + s.x];
        }
      native_view = isolate (np, carried).best_count;
    }
    for (std::size_t m = 0; m < moves.size (); ++m)
    {
      const float dz = moves[m].first, dx = moves[m].second;
      Cloud::Ptr moved;
      std::vector<unsigned char> carried;
      moveFrame (*native, native_person, dx, dz, K, moved, carried);
      for (int vw = 0; vw < 2; ++vw)
      {
        Cloud::Ptr cloud = moved;
        std::vector<unsigned char> tag = carried;
        const agex::CameraIntrinsics &Kv = vw == 0 ? K : Kp;
        if (vw == 1)
        {
          cloud.reset (new Cloud);
          agex::applyView (*moved, view, *cloud);
          tag.assign (cloud->size (), 0);
          for (int v = 0; v < view.outputHeight (); ++v)
            for (int u = 0; u < view.outputWidth (); ++u)
            {
              const cv::Point s = view.sourcePixel (u, v);
              tag[v * view.outputWidth () + u] = carried[s.y * moved->width + s.x];
            }
        }
        const Result r = isolate (cloud, tag);
        if (!dump.prefix.empty () && kf.first + "_" + kf.second == dump.keyframe)
          {
            // Depth grey (brighter = nearer), persons red, the carried person's outline green.
            cv::Mat img (cloud->height, cloud->width, CV_8UC3, cv::Scalar (0, 0, 0));
            for (int j = 0; j < static_cast<int> (cloud->size ()); ++j)
            {
              const float z = (*cloud)[j].z;
              if (!std::isfinite (z))
                continue;
              const auto g = static_cast<unsigned char> (std::max (0.f, std::min (255.f, 255.f - 40.f * z)));
              cv::Vec3b &px = img.at<cv::Vec3b> (j / cloud->width, j % cloud->width);
              px = cv::Vec3b (g, g, g);
              if (r.person[j])
                px = r.plane.head<3> ().dot ((*cloud)[j].getVector3fMap ()) + r.plane[3] < 0.04f
                         ? cv::Vec3b (255, 0, 0)
                         : cv::Vec3b (g / 3, g / 3, 255);
              if (tag[j] && !r.person[j])
                px = cv::Vec3b (0, 200, 0);
            }
            char name[256];
            std::snprintf (name, sizeof name, "%s_%.1f_%.1f_%d.png", dump.prefix.c_str (), dz, dx, vw);
            const cv::Rect crop = dump.crop & cv::Rect (0, 0, img.cols, img.rows);
            if (dump.zoom > 0 && crop.area () > 0)
              cv::resize (img (crop), img, cv::Size (), dump.zoom, dump.zoom, cv::INTER_NEAREST);
            std::vector<unsigned char> png;
            if (!cv::imencode (".png", img, png))
              throw std::runtime_error (std::string ("cannot encode the picture ") + name);
            agex::writeFileAtomic (name, std::string (png.begin (), png.end ()));
          }
        Tally &t = tallies[{m, vw}];
        ++t.frames;
        const int carried_count = static_cast<int> (std::count (tag.begin (), tag.end (), 1));
        const bool found = r.best_count > 0 && r.best_overlap > 0.5 * r.best_count;
        t.found += found;
        if (!found)
          std::printf ("missed: %s_%s dz %+.1f dx %+.1f view %d (%d persons)\n", kf.first.c_str (), kf.second.c_str (), dz, dx,
                       vw, r.persons);
        t.extra += r.persons - (found ? 1 : 0);
        t.low += r.low;
        if (found)
        {
          const double scale = (z0 / (z0 + dz)) * (z0 / (z0 + dz));
          t.ratio_scaled += r.best_count / ((vw == 0 ? native_full : native_view) * scale);
          const double carried_ratio = static_cast<double> (r.best_count) / std::max (1, carried_count);
          t.ratio_carried += carried_ratio;
          if (carried_ratio < t.worst)
          {
            t.worst = carried_ratio;
            t.worst_frame = kf.first + "_" + kf.second;
          }
          t.precision += static_cast<double> (r.best_overlap) / r.best_count;
          ++t.matched;
        }
        for (const auto &tip : tips)
        {
          const Eigen::Vector3f q = tip.point + Eigen::Vector3f (dx, 0.f, dz);
          auto &c = t.tips[tip.part];
          ++c.second;
          c.first += nearMasked (*cloud, r.person, q, Kv, 0.05f);
        }
        if (!pipeline || vw != 0)
          continue;
        // Foot tips after each stage: the data, isolation, then the pipeline with the
        // cleaning stages switched on one by one.
        auto feet = [&] (const std::string &stage, const std::vector<unsigned char> &mask, const Cloud &c) {
          auto &s = t.stage_feet[stage];
          for (const auto &tip : tips)
            if (tip.part == agex::BodyPart::Foot)
            {
              ++s.second;
              s.first += nearMasked (c, mask, tip.point + Eigen::Vector3f (dx, 0.f, dz), K, 0.05f);
            }
        };
        feet ("0 data", all, *cloud);
        feet ("1 isolation", r.person, *cloud);
        struct Variant
        {
          const char *name;
          bool mixed, median, spurs;
        };
        for (const Variant &var : {Variant{"2 +mixed", true, false, false}, Variant{"3 +mixed+median", true, true, false},
                                   Variant{"4 +all (meshes)", true, true, true}})
        {
          agex::DepthPipelineParams params;
          params.remove_mixed_pixels = var.mixed;
          params.median_window = var.median ? 3 : 1;
          if (!var.spurs)
            params.spur_iterations = 0;
          agex::DepthPipeline<pcl::PointXYZ> pipe (params);
          pipe.setInputCloud (cloud);
          agex::DepthPipelineResult result;
          pipe.compute (result);
          std::vector<unsigned char> mask (cloud->size (), 0);
          for (const auto i : result.meshIndices ())
            mask[i] = 1;
          feet (var.name, mask, *result.filtered);
          if (var.spurs)
          {
            // The meshes again without their least size: what the size takes.
            agex::DepthPipelineParams all_meshes = params;
            all_meshes.min_mesh_size = 1;
            agex::DepthPipeline<pcl::PointXYZ> pipe_all (all_meshes);
            pipe_all.setInputCloud (cloud);
            agex::DepthPipelineResult every;
            pipe_all.compute (every);
            std::vector<unsigned char> in_mesh (cloud->size (), 0);
            for (const auto i : every.meshIndices ())
              in_mesh[i] = 1;
            feet ("6 +all, any mesh size", in_mesh, *every.filtered);
            std::vector<unsigned char> left (cloud->size (), 0);
            for (std::size_t i = 0; i < cloud->size (); ++i)
              left[i] = std::isfinite ((*result.filtered)[i].z);
            feet ("5 +all (points)", left, *result.filtered);
          }
        }
      }
    }
  }
  for (const auto &entry : tallies)
  {
    const Tally &t = entry.second;
    const auto &mv = moves[entry.first.first];
    std::printf ("dz %+.1f dx %+.1f %s: found %d/%d, extra %d, %.0f px under 4 cm, pixels/scaled %.2f, pixels/carried %.2f, precision %.3f",
                 mv.first, mv.second, entry.first.second ? "144x176" : "640x480", t.found, t.frames, t.extra,
                 static_cast<double> (t.low) / std::max (1, t.frames),
                 t.matched ? t.ratio_scaled / t.matched : 0.0, t.matched ? t.ratio_carried / t.matched : 0.0,
                 t.matched ? t.precision / t.matched : 0.0);
    int all_in = 0, all_n = 0;
    for (const auto &tip : t.tips)
    {
      std::printf (", %s %d/%d", partName (tip.first), tip.second.first, tip.second.second);
      all_in += tip.second.first;
      all_n += tip.second.second;
    }
    std::printf (", tips %.3f", all_n ? static_cast<double> (all_in) / all_n : 0.0);
    if (t.matched)
      std::printf (", worst pixels/carried %.2f (%s)", t.worst, t.worst_frame.c_str ());
    std::printf ("\n");
    for (const auto &s : t.stage_feet)
      std::printf ("    feet %-18s %d/%d\n", s.first.c_str (), s.second.first, s.second.second);
  }
  return 0;
}

/** Pixels in both sets over pixels in either. */
double
iou (const std::vector<int> &a, const std::vector<int> &b)
{
  std::vector<int> x = a, y = b, both;
  std::sort (x.begin (), x.end ());
  std::sort (y.begin (), y.end ());
  std::set_intersection (x.begin (), x.end (), y.begin (), y.end (), std::back_inserter (both));
  const double either = static_cast<double> (x.size () + y.size () - both.size ());
  return either > 0 ? both.size () / either : 1.0;
}

/** Every Bonn frame at both views: persons per frame, the person's meshes against the crop
  * box's (the same cleaning stages), and the keyframe tips near the person's pixels (3 pixels
  * at 640x480, 1 at 144x176), as doc/pipeline.md reports them. */
int
runBonnAll (const std::string &shared)
{
  namespace fs = std::filesystem;
  const std::vector<agex::BonnLabel> labels = agex::readBonnLabels (shared + "/bonn/labels.csv");
  const agex::FrameView view = agex::bonnPortraitView ();
  int frames = 0, one[2] = {0, 0}, tips = 0, near[2] = {0, 0};
  double iou_sum[2] = {0, 0}, iou_min[2] = {1, 1};
  std::vector<fs::path> files;
  for (const auto &dir : fs::directory_iterator (shared + "/bonn/depth"))
    if (dir.is_directory ())
      for (const auto &f : fs::directory_iterator (dir.path ()))
        if (f.path ().extension () == ".png")
          files.push_back (f.path ());
  std::sort (files.begin (), files.end ());
  for (const auto &file : files)
  {
    const std::string sequence = file.parent_path ().filename ().string (), name = file.stem ().string ();
    const agex::Frame frame = agex::loadFrame (file.string ());
    Cloud::Ptr portrait (new Cloud);
    agex::applyView (*frame.cloud, view, *portrait);
    ++frames;
    for (int vw = 0; vw < 2; ++vw)
    {
      const Cloud::Ptr cloud = vw == 0 ? frame.cloud : portrait;
      agex::DepthPipelineParams person_params, box_params;
      box_params.isolate_people = false;
      box_params.use_crop_box = true;
      agex::DepthPipeline<pcl::PointXYZ> person_pipe (person_params), box_pipe (box_params);
      agex::DepthPipelineResult person_result, box_result;
      person_pipe.setInputCloud (cloud);
      person_pipe.compute (person_result);
      box_pipe.setInputCloud (cloud);
      box_pipe.compute (box_result);
      one[vw] += person_result.persons.size () == 1;
      const double overlap = iou (person_result.meshIndices (), box_result.meshIndices ());
      iou_sum[vw] += overlap;
      iou_min[vw] = std::min (iou_min[vw], overlap);
      std::vector<unsigned char> person (cloud->size (), 0);
      for (const auto &p : person_result.persons)
        for (const auto i : p.indices)
          person[i] = 1;
      const int w = static_cast<int> (cloud->width), h = static_cast<int> (cloud->height), r = vw == 0 ? 3 : 1;
      for (const auto &l : labels)
      {
        if (l.sequence != sequence || l.frame != name || !l.keyframe)
          continue;
        cv::Point2f t (l.tip_px.x (), l.tip_px.y ());
        if (vw == 1)
          t = view.toView (t);
        tips += vw == 0;
        bool hit = false;
        const int u0 = static_cast<int> (std::lround (t.x)), v0 = static_cast<int> (std::lround (t.y));
        for (int v = std::max (0, v0 - r); v <= std::min (h - 1, v0 + r); ++v)
          for (int u = std::max (0, u0 - r); u <= std::min (w - 1, u0 + r); ++u)
            hit = hit || person[v * w + u];
        near[vw] += hit;
      }
    }
  }
  for (int vw = 0; vw < 2; ++vw)
    std::printf ("%s: %d frames, one person in %d; person meshes against box meshes IoU %.3f mean, %.3f worst; "
                 "keyframe tips near the person %d of %d\n",
                 vw ? "144x176" : "640x480", frames, one[vw], iou_sum[vw] / std::max (1, frames), iou_min[vw], near[vw],
                 tips);
  return 0;
}

/** A synthetic dataset with person images (agex_synth --people N): of the labelled persons
  * with a visible tip at 0.8-4 m, those isolated (one found person holds at least a fifth of
  * the person's pixels and is at least half that person), and the found persons that are
  * mostly no one (doc/results.md, "Which persons isolation loses"). */
int
runDataset (const std::string &dir)
{
  std::map<std::string, std::set<int>> wanted;  // frame -> persons with a visible tip at 0.8-4 m
  {
    std::ifstream in (dir + "/labels.csv");
    if (!in)
      throw std::runtime_error (dir + "/labels.csv: cannot be read");
    std::string line;
    std::getline (in, line);
    while (std::getline (in, line))
    {
      std::vector<std::string> f;
      std::stringstream row (line);
      std::string cell;
      while (std::getline (row, cell, ','))
        f.push_back (cell);
      if (f.size () < 16)
        continue;
      const float z = std::stof (f[5]);
      if (f[13] == "1" && z >= 0.8f && z <= 4.f)
        wanted[f[0]].insert (std::stoi (f[15]));
    }
  }
  int persons = 0, isolated = 0, found_total = 0, nobody = 0, frames = 0;
  std::vector<std::string> lost;
  for (const auto &entry : std::filesystem::directory_iterator (dir + "/frames"))
  {
    const std::string frame = entry.path ().stem ().string ();
    const agex::Frame depth = agex::loadFrame (entry.path ().string ());
    const cv::Mat ids = cv::imread (dir + "/persons/" + frame + ".png", cv::IMREAD_UNCHANGED);
    if (ids.empty () || ids.cols != static_cast<int> (depth.cloud->width) || ids.rows != static_cast<int> (depth.cloud->height))
      throw std::runtime_error (dir + "/persons/" + frame + ".png: missing or not the frame's size");
    ++frames;
    agex::PersonSegmentation<pcl::PointXYZ> seg;
    seg.setInputCloud (depth.cloud);
    std::vector<pcl::PointIndices> found;
    seg.segment (found);
    found_total += static_cast<int> (found.size ());
    std::map<int, int> visible;  // person -> pixels with depth
    for (int i = 0; i < static_cast<int> (depth.cloud->size ()); ++i)
      if (std::isfinite ((*depth.cloud)[i].z) && ids.data[i] > 0)
        ++visible[ids.data[i]];
    std::set<int> kept;
    for (const auto &f : found)
    {
      std::map<int, int> votes;
      for (const auto i : f.indices)
        ++votes[ids.data[i]];
      int best = 0, best_count = 0;
      for (const auto &v : votes)
        if (v.first > 0 && v.second > best_count)
        {
          best = v.first;
          best_count = v.second;
        }
      if (best == 0 || 2 * best_count < static_cast<int> (f.indices.size ()))
      {
        ++nobody;
        const agex::PersonInfo &info = seg.getPersons ()[&f - found.data ()];
        double column = 0;
        for (const auto i : f.indices)
          column += i % depth.cloud->width;
        std::printf ("no one: %s column %.0f, %zu px, %.2f m, top %.2f, bottom %.2f, width %.2f, floor %d\n", frame.c_str (),
                     column / f.indices.size (), f.indices.size (), info.distance, info.top, info.bottom, info.width,
                     info.on_floor);
        continue;
      }
      if (5 * best_count >= visible[best])
        kept.insert (best);
    }
    for (const int k : wanted[frame])
    {
      ++persons;
      if (kept.count (k))
        ++isolated;
      else
        lost.push_back (frame + "/" + std::to_string (k));
    }
  }
  std::printf ("%d frames: %d of %d persons with a visible tip at 0.8-4 m isolated; found persons mostly no one: %d of %d\n",
               frames, isolated, persons, nobody, found_total);
  std::printf ("lost:");
  for (const auto &l : lost)
    std::printf (" %s", l.c_str ());
  std::printf ("\n");
  return 0;
}

int
runKinect (const std::string &shared)
{
  {
    const agex::Frame frame = agex::loadFrame (shared + "/kinect/five_people.pcd");
    agex::PersonSegmentation<pcl::PointXYZ> seg;
    seg.setInputCloud (frame.cloud);
    std::vector<pcl::PointIndices> persons;
    seg.segment (persons);
    std::printf ("five_people: %zu persons, floor %d\n", persons.size (), seg.getFloorFound ());
    for (std::size_t k = 0; k < persons.size (); ++k)
    {
      double col = 0;
      for (const auto i : persons[k].indices)
        col += i % frame.cloud->width;
      const agex::PersonInfo &info = seg.getPersons ()[k];
      std::printf ("  column %.0f, %.2f m, top %.2f, bottom %.2f, %d pixels\n", col / persons[k].indices.size (),
                   info.distance, info.top, info.bottom, info.points);
    }
  }
  for (const char *name : {"depth-data-1028894671", "depth-data-1045879925", "depth-data-1058893191",
                           "depth-data-1070905432", "depth-data-1166565565", "depth-data-1399145206"})
  {
    const agex::Frame frame = agex::loadFrame (shared + "/kinect/skeltrack/" + name + ".u16");
    agex::PersonSegmentation<pcl::PointXYZ> seg;
    seg.setInputCloud (frame.cloud);
    std::vector<pcl::PointIndices> persons;
    seg.segment (persons);
    std::size_t finite = 0, taken = 0;
    for (const auto &p : *frame.cloud)
      finite += std::isfinite (p.z);
    std::printf ("%s: %zu persons, floor %d,", name, persons.size (), seg.getFloorFound ());
    for (std::size_t k = 0; k < persons.size (); ++k)
    {
      taken += persons[k].indices.size ();
      std::printf (" %.2f m %d px;", seg.getPersons ()[k].distance, seg.getPersons ()[k].points);
    }
    std::printf (" %.3f of the valid pixels\n", static_cast<double> (taken) / finite);
  }
  return 0;
}
}  // namespace

int
main (int argc, char **argv)
{
  if (argc < 3)
  {
    std::cerr << "usage: person_isolation_stats bonn SHARED_DATA [SEQUENCES [SHIFTS]] [--pipeline]\n"
                 "           [--dump PREFIX KEYFRAME [--crop X,Y,W,H,ZOOM]]\n"
                 "       person_isolation_stats bonn-all SHARED_DATA\n"
                 "       person_isolation_stats dataset DIR\n"
                 "       person_isolation_stats kinect SHARED_DATA\n";
    return 2;
  }
  try
  {
    const std::string mode = argv[1], shared = argv[2];
    if (mode == "kinect")
      return runKinect (shared);
    if (mode == "bonn-all")
      return runBonnAll (shared);
    if (mode == "dataset")
      return runDataset (shared);
    std::vector<std::string> rest;
    bool pipeline = false;
    Dump dump;
    for (int a = 3; a < argc; ++a)
    {
      const std::string arg = argv[a];
      if (arg == "--pipeline")
        pipeline = true;
      else if (arg == "--dump" && a + 2 < argc)
      {
        dump.prefix = argv[++a];
        dump.keyframe = argv[++a];
      }
      else if (arg == "--crop" && a + 1 < argc)
      {
        int x = 0, y = 0, w = 0, h = 0, zoom = 0;
        if (std::sscanf (argv[++a], "%d,%d,%d,%d,%d", &x, &y, &w, &h, &zoom) != 5 || w <= 0 || h <= 0 || zoom < 1 ||
            zoom > 16)
          throw std::invalid_argument ("--crop takes x,y,width,height,zoom (zoom 1-16)");
        dump.crop = cv::Rect (x, y, w, h);
        dump.zoom = zoom;
      }
      else if (arg.rfind ("--", 0) == 0)
        throw std::invalid_argument ("unknown flag " + arg);
      else
        rest.push_back (arg);
    }
    const std::vector<std::string> sequences = splitList (rest.size () > 0 ? rest[0] : "7,8");
    const std::vector<std::string> shifts =
        splitList (rest.size () > 1 ? rest[1] : "0:0,1:0,1.5:0,2:0,1:-0.6,1:0.6,2:-0.6,2:0.6");
    return runBonn (shared, sequences, shifts, pipeline, dump);
  }
  catch (const std::exception &e)
  {
    std::cerr << "person_isolation_stats: " << e.what () << "\n";
    return 1;
  }
}
