// agex_train_forest: trains a per-pixel body-part forest (agex::BodyPartForestTrainer) from
// agex datasets, and scores a forest (ours or PCL's) per pixel on held-out frames.
//   agex_train_forest --dataset DIR[@SEQ,...] [--dataset ...] --out MODEL [options]
//   agex_train_forest --forest PATH --test-dataset DIR[@SEQ,...] [--overlay-dir DIR]
// Body pixels are the depth pipeline's meshes; a frame's per-pixel classes come from the
// dataset's label image labels/<frame>.png when there is one, else weak labels from the
// labelled tips and bases (doc/forest.md).

#include <agex/apps/command_line.h>
#include <agex/apps/dataset_selection.h>
#include <agex/apps/pipeline_flags.h>
#include <agex/apps/output.h>
#include <agex/classification/body_part_forest.h>
#include <agex/classification/body_part_forest_trainer.h>
#include <agex/classification/body_part_labeling.h>
#include <agex/classification/part_modes.h>
#include <agex/detection/depth_pipeline.h>
#include <agex/io/dataset.h>
#include <agex/io/atomic_file.h>
#include <agex/io/frame_io.h>

#include <boost/program_options.hpp>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <numeric>
#include <iostream>
#include <sstream>

#include <time.h>

namespace fs = std::filesystem;
namespace po = boost::program_options;

namespace
{
/** Weak labels from tips and bases (doc/forest.md): per part, how far from the tip towards
  * the base and how far from that axis a body pixel may be. */
struct WeakLabelParams
{
  std::array<float, 3> reach{{0.25f, 0.20f, 0.22f}};    ///< head, hand, foot: max metres along tip->base
  std::array<float, 3> radius{{0.12f, 0.06f, 0.07f}};   ///< max metres from the axis
  float beyond_tip = 0.03f;                             ///< metres the part may extend past the tip
};

constexpr int kLabelImageIgnore = 255;

/** One frame prepared for training or scoring: its filtered cloud, body pixels and classes. */
struct PreparedFrame
{
  std::string id;
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud;
  pcl::Indices body;
  std::vector<int> classes;  ///< per body pixel: 0 head, 1 hand, 2 foot, 3 other body, -1 ignore
  bool exact = false;        ///< classes from a label image
  pcl::PointCloud<agex::InterestPoint> agex_points;  ///< the pipeline's AGEX points (k of its flags)
};

/** Per part: labelled instances, and those the forest finds, split by whether an AGEX point
  * lies within 10 cm of the tip (the hands AGEX cannot name are the point of the forest). */
struct InstanceCounts
{
  std::array<std::array<std::size_t, 2>, 3> total{}, pixel_hit{}, mode_hit{}, centre_hit{};  ///< [part][agex point near?]
};

/** Classes of body pixels from the frame's labels (weak) or its label image (exact). */
bool
prepareFrame (const agex::Dataset &dataset, const std::string &id, const agex::DepthPipelineParams &pipeline,
              const WeakLabelParams &weak, bool raw_depth, PreparedFrame &out)
{
  out.id = id;
  const auto cloud = dataset.loadFrame (id);
  const agex::DepthPipelineResult prepared = agex::runDepthPipeline (cloud, pipeline);
  out.cloud = raw_depth ? cloud : prepared.filtered;
  out.agex_points = prepared.interest_points;
  out.body.clear ();
  out.classes.clear ();
  const fs::path label_image = fs::path (dataset.directory ()) / "labels" / (id + ".png");
  if (fs::exists (label_image))
  {
    // The header's size first: a damaged or foreign PNG is refused before it is decoded.
    {
      std::ifstream head_file (label_image, std::ios::binary);
      unsigned char head[24] = {};
      head_file.read (reinterpret_cast<char *> (head), sizeof head);
      std::uint64_t w = 0, h = 0;
      if (!agex::pngHeaderSize (head, static_cast<std::size_t> (head_file.gcount ()), w, h) || w != cloud->width ||
          h != cloud->height)
        throw std::runtime_error (label_image.string () + ": not a PNG of the frame's size (" +
                                  std::to_string (cloud->width) + "x" + std::to_string (cloud->height) + ")");
    }
    const cv::Mat labels = cv::imread (label_image.string (), cv::IMREAD_UNCHANGED);
    if (labels.empty () || labels.type () != CV_8UC1 || labels.cols != static_cast<int> (cloud->width) ||
        labels.rows != static_cast<int> (cloud->height))
      throw std::runtime_error (label_image.string () + ": not an 8-bit single-channel PNG of the frame's size");
    // The label image is exact: it names the body (id != 0) on the unfiltered frame.
    out.cloud = cloud;
    for (int v = 0; v < labels.rows; ++v)
      for (int u = 0; u < labels.cols; ++u)
      {
        const int id8 = labels.at<std::uint8_t> (v, u);
        const auto &p = (*cloud) (u, v);
        if (id8 == 0 || !std::isfinite (p.z))
          continue;
        out.body.push_back (v * labels.cols + u);
        out.classes.push_back (id8 == kLabelImageIgnore ? -1 : id8 <= 3 ? id8 - 1 : agex::kLabelOtherBody);
      }
    out.exact = true;
    return !out.body.empty ();
  }
  const auto labels = dataset.labelsOf (id);
  if (labels.empty ())
    return false;
  for (const auto &l : labels)
    if (!l.visible || !l.tip.allFinite () || !l.base.allFinite ())
      return false;  // a part we cannot place would be labelled "other body"
  for (const auto &mesh : prepared.meshes)
    out.body.insert (out.body.end (), mesh.indices.begin (), mesh.indices.end ());
  std::sort (out.body.begin (), out.body.end ());
  out.body.erase (std::unique (out.body.begin (), out.body.end ()), out.body.end ());
  for (const auto i : out.body)
  {
    const Eigen::Vector3f p = (*prepared.filtered)[static_cast<std::size_t> (i)].getVector3fMap ();
    int cls = agex::kLabelOtherBody;
    float nearest = std::numeric_limits<float>::infinity ();
    for (const auto &l : labels)
    {
      const int part = static_cast<int> (l.part);
      const Eigen::Vector3f axis = l.base - l.tip;
      const float length = axis.norm ();
      const Eigen::Vector3f a = length > 0.01f ? Eigen::Vector3f (axis / length) : Eigen::Vector3f::Zero ();
      const Eigen::Vector3f d = p - l.tip;
      const float t = d.dot (a);
      const float reach = std::min (weak.reach[part], std::max (length, 0.08f));
      const float off_axis = (d - t * a).norm ();
      if (t < -weak.beyond_tip || t > reach || off_axis > weak.radius[part])
        continue;
      if (d.norm () < nearest)
      {
        nearest = d.norm ();
        cls = part;
      }
    }
    out.classes.push_back (cls);
  }
  return !out.body.empty ();
}

cv::Vec3b
partColour (int part)
{
  switch (part)
  {
  case agex::kLabelHead: return {60, 60, 230};     // red (BGR)
  case agex::kLabelHand: return {60, 220, 60};     // green
  case agex::kLabelFoot: return {230, 120, 40};    // blue
  case agex::kLabelOtherBody: return {40, 200, 230};  // yellow
  default: return {160, 60, 160};                  // magenta: a labelled pixel of no part
  }
}

/** Depth grey (near bright) with the labels blended over the person, weak-label tips as white
  * circles and part-mode tips as crosses. */
cv::Mat
renderParts (const pcl::PointCloud<pcl::PointXYZ> &frame, const pcl::PointCloud<agex::BodyPartLabelPoint> &labels,
             const std::vector<agex::PartLabel> &truth, const std::vector<agex::PartMode> &modes, float fx, float fy,
             float cx, float cy)
{
  const int width = static_cast<int> (frame.width), height = static_cast<int> (frame.height);
  float zmin = std::numeric_limits<float>::max (), zmax = 0.f;
  for (const auto &p : frame.points)
    if (std::isfinite (p.z))
      zmin = std::min (zmin, p.z), zmax = std::max (zmax, p.z);
  cv::Mat image (height, width, CV_8UC3, cv::Scalar (0, 0, 0));
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u)
    {
      const float z = frame (u, v).z;
      if (std::isfinite (z))
      {
        const float t = zmax > zmin ? (z - zmin) / (zmax - zmin) : 0.f;
        const auto g = static_cast<unsigned char> (50 + 140 * (1.f - t));
        image.at<cv::Vec3b> (v, u) = cv::Vec3b (g, g, g);
      }
      const auto &q = labels (u, v);
      if (!std::isfinite (q.z))
        continue;
      const cv::Vec3b c = partColour (q.label);
      cv::Vec3b &px = image.at<cv::Vec3b> (v, u);
      for (int k = 0; k < 3; ++k)
        px[k] = static_cast<unsigned char> ((px[k] + 3 * c[k]) / 4);
    }
  const int scale = std::max (1, 480 / std::max (1, height));
  if (scale > 1)
    cv::resize (image, image, cv::Size (), scale, scale, cv::INTER_NEAREST);
  auto project = [&] (const Eigen::Vector3f &p) {
    return cv::Point (static_cast<int> ((fx * p.x () / p.z () + cx + 0.5f) * scale),
                      static_cast<int> ((fy * p.y () / p.z () + cy + 0.5f) * scale));
  };
  for (const auto &l : truth)
    if (l.visible && l.tip.allFinite ())
      cv::circle (image, project (l.tip), 7, cv::Scalar (255, 255, 255), 1, cv::LINE_AA);
  for (const auto &m : modes)
  {
    if (m.confidence < 0.3f || !m.tip.allFinite ())
      continue;
    const cv::Point p = project (m.tip);
    const cv::Vec3b c = partColour (m.part);
    cv::drawMarker (image, p, cv::Scalar (c[0], c[1], c[2]), cv::MARKER_CROSS, 14, 2);
    cv::drawMarker (image, p, cv::Scalar (0, 0, 0), cv::MARKER_CROSS, 14, 1);
  }
  return image;
}

/** This thread's CPU time in milliseconds: a timing that other processes on a busy machine
  * inflate far less than the wall clock. */
double
threadMilliseconds ()
{
  timespec ts{};
  clock_gettime (CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

double
median (std::vector<double> v)
{
  if (v.empty ())
    return 0.0;
  std::sort (v.begin (), v.end ());
  return v.size () % 2 ? v[v.size () / 2] : 0.5 * (v[v.size () / 2 - 1] + v[v.size () / 2]);
}
}  // namespace

int
main (int argc, char **argv)
{
  agex::DepthPipelineParams pipeline;
  std::vector<std::string> vector_flags, datasets, test_datasets;
  std::string out, forest_path, overlay_dir, stride_fill = "copy", instances_csv;
  agex::BodyPartForestTrainerParams params;
  WeakLabelParams weak;
  bool keyframes = false, no_balance = false, pcl_smoothing = false, raw_depth = false;
  int stride = 1, dilation = 0, repeats = 1;
  std::vector<std::string> overlay_frames;

  po::options_description general ("agex_train_forest --dataset DIR[@SEQ,...] [--dataset ...] --out MODEL [options]\n"
                                    "agex_train_forest --forest PATH --test-dataset DIR[@SEQ,...] [options]\n"
                                    "Trains a per-pixel body-part forest, or scores one per pixel");
  general.add_options () ("help,h", "show this help")
    ("dataset", po::value (&datasets)->multitoken (), "training dataset directory, optionally @sequences")
    ("out", po::value (&out), "forest model file to write")
    ("keyframes", po::bool_switch (&keyframes), "train on keyframes only")
    ("forest", po::value (&forest_path), "score this forest instead of training one: our model file, a PCL tree "
                                         "file or a directory of them (e.g. ../shared/data/pcl_people)")
    ("test-dataset", po::value (&test_datasets)->multitoken (),
     "score per-pixel accuracy on the keyframes of these datasets (after training, or of --forest)")
    ("overlay-dir", po::value (&overlay_dir), "write part maps (labels over depth) of the scored frames here")
    ("overlay-frames", po::value (&overlay_frames)->multitoken (), "only these frame ids get a part map")
    ("instances-csv", po::value (&instances_csv), "scoring: one CSV row per labelled keyframe part instance")
    ("stride", po::value (&stride)->default_value (stride), "scoring: one evaluated pixel per stride x stride cell")
    ("stride-fill", po::value (&stride_fill)->default_value (stride_fill), "scoring: skipped pixels copy|unlabelled")
    ("pcl-smoothing", po::bool_switch (&pcl_smoothing), "scoring: PCL's 5x5 label smoothing after the vote")
    ("raw-depth", po::bool_switch (&raw_depth),
     "the forest reads the frame's own depth at the body pixels, not the pipeline's denoised depth")
    ("dilation", po::value (&dilation)->default_value (dilation),
     "foreground dilation in pixels (PCL's person mask: 2), for training and scoring")
    ("time-repeats", po::value (&repeats)->default_value (repeats), "scoring: labelling runs per frame for the timing");
  po::options_description forest ("Forest (agex::BodyPartForestTrainer)");
  forest.add_options () ("trees", po::value (&params.trees)->default_value (params.trees), "trees")
    ("max-depth", po::value (&params.max_depth)->default_value (params.max_depth), "deepest tree level (<= 24)")
    ("features", po::value (&params.features_per_node)->default_value (params.features_per_node),
     "candidate offset pairs per node")
    ("thresholds", po::value (&params.thresholds_per_feature)->default_value (params.thresholds_per_feature),
     "candidate thresholds per feature")
    ("pixels-per-frame", po::value (&params.pixels_per_frame)->default_value (params.pixels_per_frame),
     "labelled pixels sampled per frame and tree")
    ("offset-range", po::value (&params.offset_range)->default_value (params.offset_range),
     "largest offset component, pixel*metres at the 525 px reference focal length")
    ("unary-probability", po::value (&params.unary_probability)->default_value (params.unary_probability, "0.3"),
     "share of features whose second probe is the pixel itself")
    ("min-samples-leaf", po::value (&params.min_samples_per_leaf)->default_value (params.min_samples_per_leaf),
     "fewest samples a split may leave on a side")
    ("min-gain", po::value (&params.min_gain)->default_value (params.min_gain, "1e-4"), "smallest gain (bits) of a split")
    ("no-balance", po::bool_switch (&no_balance), "do not weigh classes inversely to their frequency")
    ("seed", po::value (&params.seed)->default_value (params.seed), "random seed")
    ("threads", po::value (&params.threads)->default_value (params.threads), "training threads");
  po::options_description weak_options ("Weak labels from tips and bases (frames without labels/<frame>.png)");
  weak_options.add_options ()
    ("head-reach", po::value (&weak.reach[0])->default_value (weak.reach[0], "0.25"), "metres from the tip towards the base")
    ("hand-reach", po::value (&weak.reach[1])->default_value (weak.reach[1], "0.2"), "metres from the tip towards the base")
    ("foot-reach", po::value (&weak.reach[2])->default_value (weak.reach[2], "0.22"), "metres from the tip towards the base")
    ("head-radius", po::value (&weak.radius[0])->default_value (weak.radius[0], "0.12"), "metres from the tip-base axis")
    ("hand-radius", po::value (&weak.radius[1])->default_value (weak.radius[1], "0.06"), "metres from the tip-base axis")
    ("foot-radius", po::value (&weak.radius[2])->default_value (weak.radius[2], "0.07"), "metres from the tip-base axis")
    ("beyond-tip", po::value (&weak.beyond_tip)->default_value (weak.beyond_tip, "0.03"), "metres a part extends past its tip");
  po::options_description all;
  all.add (general).add (forest).add (weak_options).add (agex::apps::pipelineOptionsDescription (pipeline, vector_flags));

  try
  {
    if (!agex::apps::parseCommandLine (argc, argv, all, po::positional_options_description ()))
      return 0;
    agex::apps::finishPipelineOptions (vector_flags, pipeline);
    const bool training = forest_path.empty ();
    if (training && (datasets.empty () || out.empty ()))
      throw std::runtime_error ("--dataset and --out are required to train (or --forest to score; see --help)");
    if (!training && (!datasets.empty () || !out.empty ()))
      throw std::runtime_error ("--forest scores a forest: it takes no --dataset or --out");
    if (!training && test_datasets.empty ())
      throw std::runtime_error ("--forest needs --test-dataset");
    if (stride < 1 || repeats < 1 || dilation < 0 || (stride_fill != "copy" && stride_fill != "unlabelled"))
      throw std::runtime_error ("--stride and --time-repeats must be at least 1, --dilation not negative, "
                                "--stride-fill copy or unlabelled");
    for (int p = 0; p < 3; ++p)
      if (!(weak.reach[p] > 0.f) || !(weak.radius[p] > 0.f) || !(weak.beyond_tip >= 0.f))
        throw std::runtime_error ("weak-label reaches and radii must be positive, --beyond-tip not negative");
    if (!out.empty () && fs::is_directory (out))
      throw std::runtime_error ("--out " + out + ": a directory, not a model file");
    params.balance_classes = !no_balance;
    params.foreground_dilation = dilation;
    {
      agex::InputFiles read;
      for (const auto &spec : datasets)
        for (const auto &file : agex::apps::datasetFiles (agex::apps::selectDataset (spec, false).dataset))
          read.add (file);
      for (const auto &spec : test_datasets)
        for (const auto &file : agex::apps::datasetFiles (agex::apps::selectDataset (spec, false).dataset))
          read.add (file);
      if (!forest_path.empty ())
        read.add (forest_path);
      if (!out.empty ())
        read.checkOutput (out);
      if (!overlay_dir.empty ())
        read.checkOutput (overlay_dir);
      if (!instances_csv.empty ())
        read.checkOutput (instances_csv);
    }

    agex::BodyPartForest::ConstPtr model;
    if (training)
    {
      const auto start = std::chrono::steady_clock::now ();
      std::vector<agex::BodyPartTrainingFrame> frames;
      std::size_t exact = 0;
      nlohmann::json sources = nlohmann::json::array ();
      for (const auto &spec : datasets)
      {
        const agex::apps::DatasetSelection selection = agex::apps::selectDataset (spec, keyframes);
        agex::apps::Progress progress ("frames of " + spec, selection.frame_ids.size ());
        std::size_t used = 0;
        for (std::size_t i = 0; i < selection.frame_ids.size (); ++i)
        {
          PreparedFrame prepared;
          if (prepareFrame (selection.dataset, selection.frame_ids[i], pipeline, weak, raw_depth, prepared))
          {
            agex::BodyPartTrainingFrame f;
            f.cloud = prepared.cloud;
            f.body = std::move (prepared.body);
            f.classes = std::move (prepared.classes);
            f.fx = static_cast<float> (selection.dataset.info ().intrinsics.fx);
            f.fy = static_cast<float> (selection.dataset.info ().intrinsics.fy);
            frames.push_back (std::move (f));
            exact += prepared.exact ? 1 : 0;
            ++used;
          }
          progress.step (i + 1);
        }
        sources.push_back ({{"dataset", spec}, {"frames", used}});
      }
      if (frames.empty ())
        throw std::runtime_error ("no usable training frame (labelled, every tip visible, a body)");
      const double prepare_seconds = std::chrono::duration<double> (std::chrono::steady_clock::now () - start).count ();
      std::cout << "training on " << frames.size () << " frames (" << exact << " with label images), prepared in "
                << std::fixed << std::setprecision (1) << prepare_seconds << " s\n";
      agex::BodyPartForestTrainer trainer;
      trainer.setParams (params);
      std::unique_ptr<agex::apps::Progress> bar;
      const auto train_start = std::chrono::steady_clock::now ();
      auto forest = trainer.train (frames, [&] (std::size_t done, std::size_t total) {
        if (!bar)
          bar = std::make_unique<agex::apps::Progress> ("tree levels", total);
        bar->step (done);
      });
      const double seconds = std::chrono::duration<double> (std::chrono::steady_clock::now () - train_start).count ();
      const auto &sampled = trainer.sampledPerClass ();
      std::size_t leaves = 0;
      for (const auto &t : forest->trees ())
        leaves += t.leafCount ();
      std::ostringstream command;
      for (int i = 0; i < argc; ++i)
        command << (i ? " " : "") << argv[i];
      nlohmann::json meta = {
        {"command", command.str ()},
        {"datasets", sources},
        {"frames", frames.size ()},
        {"frames_with_label_images", exact},
        {"samples", {{"head", sampled[0]}, {"hand", sampled[1]}, {"foot", sampled[2]}, {"other_body", sampled[3]}}},
        {"params",
         {{"trees", params.trees}, {"max_depth", params.max_depth}, {"features", params.features_per_node},
          {"thresholds", params.thresholds_per_feature}, {"pixels_per_frame", params.pixels_per_frame},
          {"offset_range", params.offset_range}, {"unary_probability", params.unary_probability},
          {"min_samples_leaf", params.min_samples_per_leaf}, {"min_gain", params.min_gain},
          {"balance_classes", params.balance_classes}, {"dilation", dilation}, {"seed", params.seed}}},
        {"weak_labels",
         {{"reach", weak.reach}, {"radius", weak.radius}, {"beyond_tip", weak.beyond_tip}}},
        {"seconds", seconds}};
      forest->save (out, meta.dump ());
      std::cout << out << ": " << forest->trees ().size () << " trees, " << leaves << " leaves, "
                << forest->memoryBytes () / 1024 << " KiB, samples head " << sampled[0] << " hand " << sampled[1]
                << " foot " << sampled[2] << " other " << sampled[3] << "; trained in " << std::setprecision (1)
                << seconds << " s (" << params.threads << " threads)\n";
      model = forest;
    }
    else
    {
      const auto start = std::chrono::steady_clock::now ();
      model = agex::BodyPartForest::load (forest_path);
      std::cout << forest_path << ": " << model->trees ().size () << " trees, " << model->numClasses () << " classes, "
                << model->memoryBytes () / (1024 * 1024) << " MiB, loaded in " << std::fixed << std::setprecision (2)
                << std::chrono::duration<double> (std::chrono::steady_clock::now () - start).count () << " s\n";
    }

    if (test_datasets.empty ())
      return 0;
    if (!overlay_dir.empty ())
      fs::create_directories (overlay_dir);
    // Scoring: per-pixel confusion of the 4 parts (+ none) against the frame's classes.
    std::array<std::array<std::size_t, 5>, 4> confusion{};
    std::vector<double> ms, forest_ms, evaluated;
    InstanceCounts instances;
    std::ostringstream csv;
    csv << "frame,part,instance,agex_point_within_10cm,body_pixels_within_10cm,part_pixels_within_10cm,pixel_hit,"
           "nearest_mode_tip_m,nearest_mode_position_m\n";
    std::size_t frames = 0;
    for (const auto &spec : test_datasets)
    {
      const agex::apps::DatasetSelection selection = agex::apps::selectDataset (spec, true);
      const auto &intr = selection.dataset.info ().intrinsics;
      agex::apps::Progress progress ("scored frames of " + spec, selection.frame_ids.size ());
      for (std::size_t i = 0; i < selection.frame_ids.size (); ++i)
      {
        const std::string &id = selection.frame_ids[i];
        PreparedFrame prepared;
        if (!prepareFrame (selection.dataset, id, pipeline, weak, raw_depth, prepared))
        {
          progress.step (i + 1);
          continue;
        }
        agex::BodyPartLabeling<pcl::PointXYZ> labeling;
        labeling.setInputCloud (prepared.cloud);
        labeling.setIndices (std::make_shared<pcl::Indices> (prepared.body));
        labeling.setForest (model);
        labeling.setFocalLength (static_cast<float> (intr.fx), static_cast<float> (intr.fy));
        labeling.setStride (stride);
        labeling.setStrideFill (stride_fill == "copy" ? agex::BodyPartForest::StrideFill::Copy
                                                      : agex::BodyPartForest::StrideFill::Unlabelled);
        labeling.setPclSmoothing (pcl_smoothing);
        labeling.setForegroundDilation (dilation);
        pcl::PointCloud<agex::BodyPartLabelPoint> labels;
        std::vector<double> runs;
        for (int r = 0; r < repeats; ++r)
        {
          const double t0 = threadMilliseconds ();
          if (!labeling.compute (labels))
            throw std::runtime_error (id + ": labelling failed");
          runs.push_back (threadMilliseconds () - t0);
        }
        ms.push_back (median (runs));
        {
          // The forest pass alone (no depth image, no output cloud).
          agex::BodyPartForest::EvaluationOptions eo;
          eo.fx = static_cast<float> (intr.fx);
          eo.fy = static_cast<float> (intr.fy);
          eo.stride = stride;
          eo.fill = labeling.getStrideFill ();
          eo.pcl_smoothing = pcl_smoothing;
          eo.part_probabilities = true;  // as the stage asks for
          agex::BodyPartForest::Evaluation ev;
          std::vector<double> forest_runs;
          for (int r = 0; r < repeats; ++r)
          {
            const double t0 = threadMilliseconds ();
            model->evaluate (labeling.getDepthImage (), prepared.body, eo, ev);
            forest_runs.push_back (threadMilliseconds () - t0);
          }
          forest_ms.push_back (median (forest_runs));
        }
        evaluated.push_back (static_cast<double> (labeling.getEvaluation ().evaluated));
        ++frames;
        for (std::size_t j = 0; j < prepared.body.size (); ++j)
        {
          const int truth = prepared.classes[j];
          if (truth < 0)
            continue;
          const int got = labels[static_cast<std::size_t> (prepared.body[j])].label;
          ++confusion[truth][got < 0 ? 4 : got];
        }
        agex::PartModeEstimation modes_estimation;
        agex::PartModeParams mp;
        mp.fx = static_cast<float> (intr.fx);
        mp.fy = static_cast<float> (intr.fy);
        modes_estimation.setParams (mp);
        std::vector<agex::PartMode> modes;
        modes_estimation.compute (labels, modes);
        // Instances: a pixel hit when at least 20% of the body pixels within 10 cm of the tip
        // carry the part's label; a mode hit when a mode of the part (confidence >= 0.3) has
        // its tip within 10 cm of the labelled tip.
        for (const auto &l : selection.dataset.labelsOf (id))
        {
          if (!l.visible || !l.tip.allFinite () || !l.keyframe)
            continue;
          const int part = static_cast<int> (l.part);
          bool near_agex = false;
          for (const auto &q : prepared.agex_points)
            near_agex = near_agex || (q.getVector3fMap () - l.tip).norm () <= 0.10f;
          std::size_t near = 0, same = 0;
          for (const auto i : prepared.body)
          {
            const auto &q = labels[static_cast<std::size_t> (i)];
            if (!std::isfinite (q.z) || (q.getVector3fMap () - l.tip).norm () > 0.10f)
              continue;
            ++near;
            same += q.label == part ? 1 : 0;
          }
          bool mode_found = false, centre_found = false;
          float nearest_tip = std::numeric_limits<float>::infinity (), nearest_position = nearest_tip;
          for (const auto &m : modes)
          {
            if (m.part != part || m.confidence < 0.3f)
              continue;
            mode_found = mode_found || (m.tip - l.tip).norm () <= 0.10f;
            centre_found = centre_found || (m.position - l.tip).norm () <= 0.10f;
            nearest_tip = std::min (nearest_tip, (m.tip - l.tip).norm ());
            nearest_position = std::min (nearest_position, (m.position - l.tip).norm ());
          }
          csv << id << "," << agex::labelPartName (part) << "," << l.instance << "," << near_agex << "," << near << ","
              << same << "," << (near > 0 && same * 5 >= near) << "," << nearest_tip << "," << nearest_position << "\n";
          ++instances.total[part][near_agex];
          instances.pixel_hit[part][near_agex] += (near > 0 && same * 5 >= near) ? 1 : 0;
          instances.mode_hit[part][near_agex] += mode_found ? 1 : 0;
          instances.centre_hit[part][near_agex] += centre_found ? 1 : 0;
        }
        if (!overlay_dir.empty () &&
            (overlay_frames.empty () || std::find (overlay_frames.begin (), overlay_frames.end (), id) != overlay_frames.end ()))
        {
          const auto frame = selection.dataset.loadFrame (id);
          agex::apps::writePng ((fs::path (overlay_dir) / (id + ".png")).string (),
                                renderParts (*frame, labels, selection.dataset.labelsOf (id), modes,
                                             static_cast<float> (intr.fx), static_cast<float> (intr.fy),
                                             static_cast<float> (intr.cx), static_cast<float> (intr.cy)));
        }
        progress.step (i + 1);
      }
    }
    if (!instances_csv.empty ())
      agex::writeFileAtomic (instances_csv, csv.str ());
    std::size_t total = 0, correct = 0;
    double recall_sum = 0.0;
    int recall_classes = 0;
    std::cout << "scored " << frames << " keyframes; per-pixel (rows: label, columns: forest head hand foot other none)\n";
    for (int t = 0; t < 4; ++t)
    {
      std::size_t row = 0;
      for (int g = 0; g < 5; ++g)
        row += confusion[t][g];
      total += row;
      correct += confusion[t][t];
      std::cout << "  " << std::setw (10) << std::left << agex::labelPartName (t) << std::right;
      for (int g = 0; g < 5; ++g)
        std::cout << std::setw (9) << confusion[t][g];
      if (row)
      {
        const double recall = static_cast<double> (confusion[t][t]) / row;
        recall_sum += recall;
        ++recall_classes;
        std::cout << "   recall " << std::setprecision (3) << recall;
      }
      std::cout << "\n";
    }
    std::cout << std::setprecision (3) << "accuracy " << (total ? static_cast<double> (correct) / total : 0.0)
              << ", mean class recall " << (recall_classes ? recall_sum / recall_classes : 0.0) << "\n";
    std::cout << "labelled instances found (pixels: >= 20% of the body within 10 cm of the tip carry the part; "
                 "mode tips: a part mode of confidence >= 0.3 with its tip within 10 cm), by whether an AGEX point "
                 "(k = " << pipeline.k << ") lies within 10 cm:\n";
    for (int p = 0; p < 3; ++p)
      for (int a = 1; a >= 0; --a)
        std::cout << "  " << std::setw (5) << std::left << agex::labelPartName (p) << std::right
                  << (a ? " near an AGEX point " : " no AGEX point near ") << instances.total[p][a]
                  << ": pixels " << instances.pixel_hit[p][a] << ", mode tips " << instances.mode_hit[p][a]
                  << " (mode positions " << instances.centre_hit[p][a] << ")\n";
    std::cout << std::setprecision (3) << "labelling CPU ms per frame (stride " << stride << ", 1 thread): median "
              << median (ms) << ", mean " << (ms.empty () ? 0.0 : std::accumulate (ms.begin (), ms.end (), 0.0) / ms.size ())
              << ", max " << (ms.empty () ? 0.0 : *std::max_element (ms.begin (), ms.end ())) << "; the forest pass alone: median "
              << median (forest_ms) << ", max " << (forest_ms.empty () ? 0.0 : *std::max_element (forest_ms.begin (), forest_ms.end ()))
              << "; pixels run "
              << std::setprecision (0) << median (evaluated) << " (median)\n";
    return 0;
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_train_forest: error: " << e.what () << "\n";
    return 1;
  }
}
