#include <agex/apps/evaluation_runs.h>

#include <agex/apps/command_line.h>
#include <agex/apps/eval_flags.h>
#include <agex/apps/output_guard.h>
#include <agex/apps/output.h>
#include <agex/common/statistics.h>
#include <agex/detection/coverage_evaluation.h>
#include <agex/detection/detection_evaluation.h>
#include <agex/detection/person_evaluation.h>
#include <agex/detection/part_label_training.h>
#include <agex/classification/body_part_labeling.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>

namespace agex
{
namespace apps
{
namespace
{
/** Adds the precision-recall curve of one class to a plot. */
void
addPrecisionRecall (Plot &plot, const agex::DetectionEvaluation &evaluation, agex::BodyPart part,
                    const std::string &label, const cv::Scalar &colour)
{
  char name[96];
  std::snprintf (name, sizeof name, "%s AP %.2f", label.c_str (), evaluation.averagePrecision (part));
  Plot::Series series{name, colour, {}};
  for (const auto &[recall, precision] : evaluation.precisionRecall (part))
    series.points.emplace_back (recall, precision);
  plot.series.push_back (series);
}

/** The median of frame times (0 for no frames: a count, not a missing value). */
double
medianMs (const std::vector<double> &ms)
{
  return ms.empty () ? 0.0 : agex::median (ms);
}

/** One detector's side of the comparison. */
struct Contender
{
  Contender (float min_iou, float focal, float radius)
    : by_overlap (agex::DetectionEvaluation::boxOverlap (min_iou, focal)), by_distance (radius)
  {
  }
  agex::DetectionEvaluation by_overlap, by_distance;
  std::vector<double> frame_ms;
  double detections = 0.0, patches = 0.0;

  void add (const std::vector<agex::BodyPartDetection> &detections_found, const std::vector<agex::PartLabel> &labels,
            double ms, std::size_t patches_classified)
  {
    patches += static_cast<double> (patches_classified);
    by_overlap.addFrame (detections_found, labels);
    by_distance.addFrame (detections_found, labels);
    frame_ms.push_back (ms);
    detections += static_cast<double> (detections_found.size ());
  }
  nlohmann::json report () const
  {
    auto number = [] (double v) { return std::isfinite (v) ? nlohmann::json (v) : nlohmann::json (nullptr); };
    nlohmann::json doc;
    for (int c = 0; c < agex::kBodyPartCount; ++c)
    {
      const auto part = static_cast<agex::BodyPart> (c);
      doc["ap"]["iou"][agex::bodyPartName (part)] = number (by_overlap.averagePrecision (part));
      doc["ap"]["distance"][agex::bodyPartName (part)] = number (by_distance.averagePrecision (part));
    }
    doc["ms_per_frame"] = medianMs (frame_ms);
    doc["detections_per_frame"] = frame_ms.empty () ? 0.0 : detections / frame_ms.size ();
    // What the time mostly buys, and unlike it independent of the machine's load.
    doc["patches_classified_per_frame"] = frame_ms.empty () ? 0.0 : patches / frame_ms.size ();
    return doc;
  }
};

}  // namespace

int
evaluateCoverage (const DatasetSelection &selection, agex::DepthPipelineParams params, int k,
                  float radius, bool keyframes_only, bool details, const std::string &json_path,
                  const std::string &plot_path)
{
  constexpr int kCurveMax = 20;
  const int max_k = std::max (k, kCurveMax);
  params.k = max_k + 1;  // the centroid and max_k extrema per mesh
  agex::CoverageEvaluation evaluation (max_k, radius);
  evaluation.setDetailK (k);

  const agex::Dataset &dataset = selection.dataset;
  const std::vector<std::string> &ids = selection.frame_ids;
  Progress progress ("evaluated", ids.size ());
  double total_ms = 0.0;
  std::size_t meshes = 0;
  for (std::size_t i = 0; i < ids.size (); ++i)
  {
    const auto cloud = dataset.loadFrame (ids[i]);
    const agex::DepthPipelineResult result = agex::runDepthPipeline (cloud, params);
    total_ms += result.ms.back ().second;
    meshes += result.meshes.size ();
    evaluation.addFrame (result.interest_points, dataset.labelsOf (ids[i]));
    progress.step (i + 1);
  }

  nlohmann::json doc = evaluation.report (k);
  doc["dataset"] = dataset.directory ();
  doc["keyframes_only"] = keyframes_only;
  doc["pipeline_ms_per_frame"] = ids.empty () ? 0.0 : total_ms / ids.size ();
  doc["meshes_per_frame"] = ids.empty () ? 0.0 : static_cast<double> (meshes) / ids.size ();
  if (details)
    doc["labels_detail"] = evaluation.details ();
  if (!json_path.empty ())
    writeJson (json_path, doc);

  std::cout << dataset.directory () << ": " << ids.size () << " frames, k = " << k << " extrema, R = " << radius
            << " m\n";
  for (int c = 0; c < agex::kBodyPartCount; ++c)
  {
    const auto part = static_cast<agex::BodyPart> (c);
    std::printf ("  %-5s coverage %.3f (centroid counted: %.3f) of %zu labels, orientation median %.1f deg\n",
                 agex::bodyPartName (part), evaluation.coverage (part, k), evaluation.coverageCountingCentroid (part, k),
                 evaluation.labelCount (part), evaluation.orientationMedianDeg (part));
  }

  if (!plot_path.empty ())
  {
    Plot plot;
    plot.title = "AGEX coverage: tips within " + std::to_string (static_cast<int> (radius * 100 + 0.5)) +
                 " cm of the first k extrema (" + std::to_string (ids.size ()) + " frames)";
    plot.x_label = "k (extrema)";
    plot.y_label = "coverage";
    plot.x_min = 0;
    plot.x_max = max_k;
    plot.x_tick = 2;
    for (int c = 0; c < agex::kBodyPartCount; ++c)
    {
      const auto part = static_cast<agex::BodyPart> (c);
      Plot::Series series{agex::bodyPartName (part), bodyPartColour (c), {}};
      series.points.emplace_back (0.0, 0.0);
      for (int kk = 1; kk <= max_k; ++kk)
        series.points.emplace_back (kk, evaluation.coverage (part, kk));
      plot.series.push_back (series);
    }
    writePng (plot_path, renderPlot (plot));
  }
  return 0;
}
namespace
{
/** What agex_eval detect gathered over some frames, mergeable with another share's. */
struct DetectionTally
{
  explicit DetectionTally (float radius) : evaluation (radius), candidates (radius), persons (radius) {}
  agex::DetectionEvaluation evaluation;
  agex::CandidateCoverage candidates;
  agex::PersonEvaluation persons;
  std::vector<double> frame_ms;

  nlohmann::json state () const
  {
    return {{"evaluation", evaluation.state ()}, {"candidates", candidates.state ()}, {"persons", persons.state ()},
            {"frame_ms", frame_ms}};
  }
  /** \throws std::invalid_argument naming source on a malformed state */
  void merge (const nlohmann::json &state, const std::string &source)
  {
    if (!state.is_object () || !state.contains ("evaluation") || !state.contains ("candidates") ||
        !state.contains ("frame_ms") || !state["frame_ms"].is_array ())
      throw std::invalid_argument (source + ": \"state\" must hold evaluation, candidates and frame_ms");
    evaluation.merge (agex::DetectionEvaluation::fromState (state["evaluation"], source));
    candidates.merge (agex::CandidateCoverage::fromState (state["candidates"], source));
    if (!state.contains ("persons"))
      throw std::invalid_argument (source + ": \"state\" must hold persons");
    persons.merge (agex::PersonEvaluation::fromState (state["persons"], source));
    for (const auto &ms : state["frame_ms"])
    {
      if (!ms.is_number () || !std::isfinite (ms.get<double> ()) || ms.get<double> () < 0.0)
        throw std::invalid_argument (source + ": state frame_ms must hold non-negative numbers");
      frame_ms.push_back (ms.get<double> ());
    }
  }
};

/** The frames [first, last) of the selection through the detector. */
void
tallyDetection (const DatasetSelection &selection, const LoadedDetector &loaded, std::size_t first, std::size_t last,
                DetectionTally &tally)
{
  agex::BodyPartDetector<pcl::PointXYZ> detector;
  loaded.configure (detector);
  const auto &intr = selection.dataset.info ().intrinsics;
  detector.setFocalLength (static_cast<float> (intr.fx), static_cast<float> (intr.fy));
  Progress progress ("evaluated", last - first);
  for (std::size_t i = first; i < last; ++i)
  {
    const auto &id = selection.frame_ids[i];
    const auto cloud = selection.dataset.loadFrame (id);
    const auto start = std::chrono::steady_clock::now ();
    detector.setInputCloud (cloud);
    std::vector<agex::BodyPartDetection> detections;
    detector.compute (detections);
    tally.frame_ms.push_back (agex::msSince (start));
    tally.evaluation.addFrame (detections, selection.dataset.labelsOf (id));
    tally.candidates.addFrame (detector.getIntermediate ().interest_points, detector.getCandidates (),
                               selection.dataset.labelsOf (id));
    const cv::Mat person_image =
        selection.dataset.hasPersonLabels () ? selection.dataset.loadPersonLabels (id) : cv::Mat ();
    tally.persons.addFrame (detections, selection.dataset.labelsOf (id), &person_image);
    progress.step (i + 1 - first);
  }
}

/** The report of a tally: JSON (with what names the run, `about`), the printed figures, the plot. */
int
reportDetection (const DetectionTally &tally, const nlohmann::json &about, const std::string &json_path,
                 const std::string &plots_dir, const nlohmann::json &extra = nlohmann::json::object ())
{
  constexpr float kConfusionThreshold = 0.75f;
  const agex::DetectionEvaluation &evaluation = tally.evaluation;
  nlohmann::json doc = evaluation.report (kConfusionThreshold);
  doc.update (about);
  doc["ms_per_frame_median"] = medianMs (tally.frame_ms);
  doc["candidate_coverage"] = tally.candidates.report ();
  doc["people"] = tally.persons.report ();
  doc.update (extra);
  if (!json_path.empty ())
    writeJson (json_path, doc);
  std::cout << about["dataset"].get<std::string> () << ": " << evaluation.frames () << " frames\n";
  for (int c = 0; c < agex::kBodyPartCount; ++c)
  {
    const auto part = static_cast<agex::BodyPart> (c);
    std::printf ("  %-5s AP %.3f, orientation median %.1f deg\n", agex::bodyPartName (part),
                 evaluation.averagePrecision (part), evaluation.orientationMedianDeg (part));
  }
  if (!plots_dir.empty ())
  {
    std::filesystem::create_directories (plots_dir);
    Plot plot;
    plot.title = "Body-part detection: precision against recall (" + std::to_string (evaluation.frames ()) +
                 " frames)";
    plot.x_label = "recall";
    plot.y_label = "precision";
    for (int c = 0; c < agex::kBodyPartCount; ++c)
      addPrecisionRecall (plot, evaluation, static_cast<agex::BodyPart> (c), agex::bodyPartName (static_cast<agex::BodyPart> (c)),
                          bodyPartColour (c));
    writePng ((std::filesystem::path (plots_dir) / "precision_recall.png").string (),
                          renderPlot (plot));
  }
  return 0;
}

/** The keys of a detect report that say what was evaluated how: equal in every share. */
const char *const kRunKeys[] = {"dataset", "model", "detector_mode", "forest", "radius_m", "min_iou",
                                "cascade_min_confidence", "cascade_miss_rate", "tip_radius", "tip_min_confidence", "window_model", "window_weight"};
}  // namespace

int
evaluateDetection (const DatasetSelection &selection, const LoadedDetector &loaded, float radius,
                   const std::string &json_path, const std::string &plots_dir, ProcessGroup &group, const Shard &shard)
{
  nlohmann::json about = {{"dataset", selection.dataset.directory ()}, {"model", loaded.files.front ()},
                          {"detector_mode", loaded.mode_name},
                          {"cascade_min_confidence", loaded.cascade_min_confidence},
                          {"cascade_miss_rate", loaded.cascade_miss_rate},
                          {"tip_radius", loaded.tip_refinement.radius},
                          {"tip_min_confidence", loaded.tip_refinement.min_relative_confidence},
                          {"window_model", loaded.window_file},
                          {"window_weight", loaded.window_model ? loaded.window_weight : 0.f}};
  if (!loaded.forest_file.empty ())
    about["forest"] = loaded.forest_file;
  if (loaded.mode == DetectorMode::Forest)
  {
    about["forest_input"] = forestInputName (loaded.forest_parts.input);
    about["forest_parts"] = partProposalsName (loaded.forest_parts.proposals);
  }
  const std::size_t frames = selection.frame_ids.size ();
  DetectionTally tally (radius);
  if (!group.distributed ())
  {
    if (!shard.given)
    {
      tallyDetection (selection, loaded, 0, frames, tally);
      return reportDetection (tally, about, json_path, plots_dir);
    }
    if (json_path.empty ())
      throw std::runtime_error ("--shard needs --json: the part's report holds the state that --merge joins");
    const auto [first, last] = shardRange (frames, shard.index, shard.count);
    tallyDetection (selection, loaded, first, last, tally);
    const nlohmann::json extra = {
        {"shard", {{"index", shard.index}, {"count", shard.count}, {"first_frame", first}, {"dataset_frames", frames}}},
        {"state", tally.state ()}};
    return reportDetection (tally, about, json_path, plots_dir, extra);
  }
  if (shard.given)
    throw std::runtime_error ("--shard and mpirun both split the frames; use one of them");
  // Under mpirun: each rank its share, rank 0 merges the states in rank order (= frame order).
  const auto [first, last] = shardRange (frames, group.rank (), group.size ());
  std::string mine;
  try
  {
    tallyDetection (selection, loaded, first, last, tally);
    mine = "1" + tally.state ().dump ();
  }
  catch (const std::exception &e)
  {
    mine = std::string ("0") + e.what ();
  }
  const std::vector<std::string> all = group.gather (mine);
  if (mine[0] != '1')
    throw std::runtime_error ("rank " + std::to_string (group.rank ()) + ": " + mine.substr (1));
  if (group.rank () > 0)
    return 0;
  DetectionTally merged (radius);
  for (std::size_t r = 0; r < all.size (); ++r)
  {
    if (all[r][0] != '1')
      throw std::runtime_error ("rank " + std::to_string (r) + " failed (see its message); no report written");
    merged.merge (nlohmann::json::parse (all[r].substr (1)), "rank " + std::to_string (r));
  }
  return reportDetection (merged, about, json_path, plots_dir);
}

int
mergeDetectionEvaluations (const std::vector<std::string> &parts, const std::string &json_path,
                           const std::string &plots_dir)
{
  if (json_path.empty ())
    throw std::runtime_error ("--merge needs --json OUT, the report to write");
  std::map<int, std::pair<std::string, nlohmann::json>> by_index;
  int count = -1;
  nlohmann::json about;
  float radius = 0.f;
  for (const auto &path : parts)
  {
    std::ifstream in (path, std::ios::binary);
    if (!in)
      throw std::runtime_error (path + ": cannot be read");
    constexpr int kMaxDepth = 64;
    nlohmann::json doc = nlohmann::json::parse (
        in, [] (int depth, nlohmann::json::parse_event_t, nlohmann::json &) { return depth <= kMaxDepth; }, false);
    if (!doc.is_object () || !doc.contains ("shard") || !doc.contains ("state") || !doc["shard"].is_object () ||
        !doc["shard"].contains ("index") || !doc["shard"].contains ("count") ||
        !doc["shard"]["index"].is_number_integer () || !doc["shard"]["count"].is_number_integer ())
      throw std::runtime_error (path + ": not the report of an agex_eval detect --shard run (no \"shard\" and \"state\")");
    // Read wide: a count past int would wrap into one that looks plausible.
    const std::int64_t index64 = doc["shard"]["index"].get<std::int64_t> (), n64 = doc["shard"]["count"].get<std::int64_t> ();
    constexpr std::int64_t kMaxShards = 100000;  // as --shard allows
    if (n64 < 1 || n64 > kMaxShards || index64 < 0 || index64 >= n64)
      throw std::runtime_error (path + ": \"shard\" says part " + std::to_string (index64) + " of " + std::to_string (n64) +
                                ", but a --shard run is part K of N with 0 <= K < N <= " + std::to_string (kMaxShards));
    const int index = static_cast<int> (index64), n = static_cast<int> (n64);
    nlohmann::json run;
    for (const char *key : kRunKeys)
      if (doc.contains (key))
        run[key] = doc[key];
    if (count < 0)
    {
      count = n;
      about = run;
      radius = doc.contains ("radius_m") && doc["radius_m"].is_number () ? doc["radius_m"].get<float> () : 0.f;
    }
    else if (n != count || run != about)
      throw std::runtime_error (path + ": a shard of another run (shard count, dataset, model, mode, radius or a detector setting differ "
                                       "from " + by_index.begin ()->second.first + "'s)");
    if (index < 0 || index >= n)
      throw std::runtime_error (path + ": shard " + std::to_string (index) + " of " + std::to_string (n) + "?");
    if (!by_index.emplace (index, std::make_pair (path, std::move (doc["state"]))).second)
      throw std::runtime_error (path + ": shard " + std::to_string (index) + " is given twice (also " +
                                by_index[index].first + ")");
  }
  if (parts.empty ())
    throw std::runtime_error ("--merge needs the reports of the --shard runs");
  if (static_cast<int> (by_index.size ()) != count)
  {
    std::string missing;
    for (int k = 0; k < count; ++k)
      if (!by_index.count (k))
        missing += (missing.empty () ? "" : ", ") + std::to_string (k);
    throw std::runtime_error ("shard(s) " + missing + " of " + std::to_string (count) + " missing; merge them all");
  }
  InputFiles read (parts);
  checkOutputPath (json_path, "agex_eval report", evalReportRecogniser (), read);
  if (!plots_dir.empty ())
  {
    read.checkOutput (plots_dir);
    checkPngsInFolder (evalPlotFiles ("detect", plots_dir), read);
  }
  DetectionTally tally (radius);
  for (const auto &[index, part] : by_index)
    tally.merge (part.second, part.first);
  const std::string dataset = about.contains ("dataset") && about["dataset"].is_string () ? about["dataset"].get<std::string> () : "";
  about["dataset"] = dataset;
  return reportDetection (tally, about, json_path, plots_dir);
}

int
compareDetectors (const DatasetSelection &selection, const std::string &agex_model_path,
                  const std::string &sw_model_path, const std::string &fused_model_path,
                  const agex::SlidingWindowParams &window_override, float radius, float min_iou,
                  const std::string &json_path, const std::string &plots_dir)
{
  // The fused detector beside the paper's two (when a fused model is given).
  agex::BodyPartDetector<pcl::PointXYZ>::Ptr fused_detector;
  if (!fused_model_path.empty ())
  {
    fused_detector = agex::BodyPartDetector<pcl::PointXYZ>::fromModel (fused_model_path);
    if (fused_detector->getModel ()->settings ().kind != agex::DetectorKind::Fused)
      throw std::runtime_error (fused_model_path + " is not a fused model (train one with agex_train --fused)");
    const auto &intr = selection.dataset.info ().intrinsics;
    fused_detector->setFocalLength (static_cast<float> (intr.fx), static_cast<float> (intr.fy));
  }
  const auto agex_model = std::make_shared<const agex::DetectorModel> (agex::DetectorModel::load (agex_model_path));
  agex_model->requireKind (agex::DetectorKind::Agex, agex_model_path);
  const auto sw_model = std::make_shared<const agex::DetectorModel> (agex::DetectorModel::load (sw_model_path));
  sw_model->requireKind (agex::DetectorKind::SlidingWindow, sw_model_path);
  agex::BodyPartDetector<pcl::PointXYZ> agex_detector, sw_detector;
  agex_detector.setModel (agex_model);
  sw_detector.setModel (sw_model);
  // Every detector classifies every candidate in full here (the sliding window has no soft
  // cascade below its minimum confidence): the comparison is of the classifiers.
  agex_detector.setCascadeMinConfidence (0.f);
  if (fused_detector)
    fused_detector->setCascadeMinConfidence (0.f);
  agex::DetectorSettings sw_settings = sw_model->settings ();
  if (window_override.stride > 0)
    sw_settings.sliding_window.stride = window_override.stride;
  if (!window_override.scales.empty ())
    sw_settings.sliding_window.scales = window_override.scales;
  sw_detector.setSettings (sw_settings);
  const float focal = static_cast<float> (selection.dataset.info ().intrinsics.fx);
  if (!(focal > 0.f))
    throw std::runtime_error (selection.dataset.directory () + ": the dataset has no focal length (intrinsics.fx)");
  constexpr int kContainmentK = 5;
  Contender agex_side (min_iou, focal, radius), sw_side (min_iou, focal, radius), fused_side (min_iou, focal, radius);
  agex::CoverageEvaluation containment (kContainmentK, radius);

  Progress progress ("compared", selection.frame_ids.size ());
  for (std::size_t i = 0; i < selection.frame_ids.size (); ++i)
  {
    const auto &id = selection.frame_ids[i];
    const auto cloud = selection.dataset.loadFrame (id);
    const auto labels = selection.dataset.labelsOf (id);

    auto start = std::chrono::steady_clock::now ();
    std::vector<agex::BodyPartDetection> found, windows_found;
    agex_detector.setInputCloud (cloud);
    agex_detector.compute (found);
    agex_side.add (found, labels, agex::msSince (start), agex_detector.getPatchesClassified ());
    containment.addFrame (agex_detector.getIntermediate ().interest_points, labels);

    start = std::chrono::steady_clock::now ();
    sw_detector.setInputCloud (cloud);
    sw_detector.compute (windows_found);
    double ms = agex::msSince (start);
    // The pipeline also ran AGEX, which the baseline does not need: not its time.
    for (const auto &[stage, stage_ms] : sw_detector.getIntermediate ().ms)
      if (stage == "agex")
        ms -= stage_ms;
    sw_side.add (windows_found, labels, ms, sw_detector.getPatchesClassified ());
    if (fused_detector)
    {
      std::vector<agex::BodyPartDetection> fused_found;
      start = std::chrono::steady_clock::now ();
      fused_detector->setInputCloud (cloud);
      fused_detector->compute (fused_found);
      fused_side.add (fused_found, labels, agex::msSince (start), fused_detector->getPatchesClassified ());
    }
    progress.step (i + 1);
  }

  const std::size_t frames = selection.frame_ids.size ();
  nlohmann::json doc;
  doc["dataset"] = selection.dataset.directory ();
  doc["frames"] = frames;
  doc["criteria"] = {{"iou", {{"min_iou", min_iou},
                              {"focal_length_px", focal},
                              {"box_side_m", {{"head", agex::partBoxSide (agex::BodyPart::Head)},
                                              {"hand", agex::partBoxSide (agex::BodyPart::Hand)},
                                              {"foot", agex::partBoxSide (agex::BodyPart::Foot)}}}}},
                     {"distance", {{"radius_m", radius}}}};
  doc["agex"] = agex_side.report ();
  doc["agex"]["model"] = agex_model_path;
  doc["sliding_window"] = sw_side.report ();
  doc["sliding_window"]["model"] = sw_model_path;
  if (sw_settings.sliding_window.stride > 0)
    doc["sliding_window"]["stride_px"] = sw_settings.sliding_window.stride;
  else
    doc["sliding_window"]["stride_metres"] = sw_settings.sliding_window.stride_metres;
  doc["sliding_window"]["scales"] = sw_settings.sliding_window.scales;
  if (fused_detector)
  {
    doc["fused"] = fused_side.report ();
    doc["fused"]["model"] = fused_model_path;
    // The fused model as it ships: with the window model it names blended in, if any.
    doc["fused"]["window_model"] = fused_detector->getWindowModel () ? fused_detector->getModel ()->windowPath () : "";
    doc["fused"]["window_weight"] = fused_detector->getWindowModel () ? fused_detector->getWindowWeight () : 0.f;
  }
  for (int c = 0; c < agex::kBodyPartCount; ++c)
  {
    const auto part = static_cast<agex::BodyPart> (c);
    const std::size_t labels = containment.labelCount (part);
    // A class without labels has no fraction (null), and its count stays an integer.
    const nlohmann::json fraction = labels ? nlohmann::json (containment.coverage (part, kContainmentK)) : nlohmann::json ();
    doc["agex5_containment"][agex::bodyPartName (part)] = {
        {"contained", containment.coveredCount (part, kContainmentK)}, {"labels", labels}, {"fraction", fraction}};
  }
  doc["agex5_containment"]["radius_m"] = radius;
  if (!json_path.empty ())
    writeJson (json_path, doc);

  std::cout << selection.dataset.directory () << ": " << frames << " frames\n";
  for (const auto *side : {&agex_side, &sw_side, &fused_side})
  {
    if (side == &fused_side && !fused_detector)
      continue;
    std::printf ("  %-14s %7.1f ms/frame %6.0f patches/frame  AP IoU>%.2f:",
                 side == &agex_side ? "AGEX" : side == &sw_side ? "sliding window" : "fused", medianMs (side->frame_ms),
                 side->patches / std::max<std::size_t> (1, frames), min_iou);
    for (const auto part : {agex::BodyPart::Head, agex::BodyPart::Hand, agex::BodyPart::Foot})
      std::printf (" %s %.3f", agex::bodyPartName (part), side->by_overlap.averagePrecision (part));
    std::printf ("  %.0f cm:", radius * 100.0);
    for (const auto part : {agex::BodyPart::Head, agex::BodyPart::Hand, agex::BodyPart::Foot})
      std::printf (" %s %.3f", agex::bodyPartName (part), side->by_distance.averagePrecision (part));
    std::printf ("\n");
  }
  for (const char *part : {"head", "hand", "foot"})
    std::printf ("  AGEX_5 contains %zu/%zu %s labels\n", doc["agex5_containment"][part]["contained"].get<std::size_t> (),
                 doc["agex5_containment"][part]["labels"].get<std::size_t> (), part);

  if (!plots_dir.empty ())
  {
    std::filesystem::create_directories (plots_dir);
    for (const auto part : {agex::BodyPart::Head, agex::BodyPart::Hand, agex::BodyPart::Foot})
    {
      Plot plot;
      plot.title = std::string (agex::bodyPartName (part)) + ": AGEX against sliding windows (" +
                   std::to_string (frames) + " frames)";
      plot.x_label = "recall";
      plot.y_label = "precision";
      char overlap[32], distance[32];
      std::snprintf (overlap, sizeof overlap, "IoU > %.2g", min_iou);
      std::snprintf (distance, sizeof distance, "%.0f cm", radius * 100.0);
      addPrecisionRecall (plot, agex_side.by_overlap, part, std::string ("AGEX, ") + overlap, cv::Scalar (0, 0, 200));
      addPrecisionRecall (plot, sw_side.by_overlap, part, std::string ("sliding window, ") + overlap,
                          cv::Scalar (200, 80, 0));
      addPrecisionRecall (plot, agex_side.by_distance, part, std::string ("AGEX, ") + distance,
                          cv::Scalar (120, 120, 255));
      addPrecisionRecall (plot, sw_side.by_distance, part, std::string ("sliding window, ") + distance,
                          cv::Scalar (240, 190, 120));
      if (fused_detector)
        addPrecisionRecall (plot, fused_side.by_distance, part, std::string ("fused, ") + distance,
                            cv::Scalar (40, 160, 40));
      writePng ((std::filesystem::path (plots_dir) / ("compare_" + std::string (agex::bodyPartName (part)) +
                                                                   ".png")).string (),
                            renderPlot (plot));
    }
  }
  return 0;
}
int
evaluatePartLabels (const DatasetSelection &selection, const LoadedDetector &loaded, const WeakPartLabelParams &weak,
                    const std::string &json_path, const std::string &overlay_dir)
{
  if (!loaded.forest)
    throw std::runtime_error ("agex_eval parts needs --forest");
  const auto &intr = selection.dataset.info ().intrinsics;
  const DepthPipelineParams &pipeline = loaded.model->settings ().pipeline;
  PartLabelEvaluation evaluation;
  std::vector<double> frame_ms;
  if (!overlay_dir.empty ())
    std::filesystem::create_directories (overlay_dir);
  Progress progress ("scored", selection.frame_ids.size ());
  for (std::size_t i = 0; i < selection.frame_ids.size (); ++i)
  {
    const std::string &id = selection.frame_ids[i];
    PartLabelledFrame frame;
    if (partLabelledFrame (selection.dataset, id, pipeline, weak, false, frame))
    {
      const auto start = std::chrono::steady_clock::now ();
      // The cloud is the working frame (DepthPipelineParams::working_spacing): f / stride.
      const float fx = static_cast<float> (intr.fx) / static_cast<float> (frame.prepared.stride);
      const float fy = static_cast<float> (intr.fy) / static_cast<float> (frame.prepared.stride);
      BodyPartLabeling<pcl::PointXYZ> labeling;
      labeling.setInputCloud (frame.cloud);
      labeling.setIndices (std::make_shared<pcl::Indices> (frame.body));
      labeling.setForest (loaded.forest);
      labeling.setFocalLength (fx, fy);
      labeling.setStride (forestStrideFor (loaded.forest_stride, fx));
      pcl::PointCloud<BodyPartLabelPoint> labels;
      if (!labeling.compute (labels))
        throw std::runtime_error (id + ": labelling failed");
      frame_ms.push_back (msSince (start));
      evaluation.addFrame (frame, labels);
      if (!overlay_dir.empty ())
      {
        PartModeEstimation modes_estimation;
        PartModeParams mp;
        mp.fx = fx;
        mp.fy = fy;
        modes_estimation.setParams (mp);
        std::vector<PartMode> modes;
        modes_estimation.compute (labels, modes);
        // Drawn on the frame the labels are pixels of; the labelled tips are the input's pixels.
        std::vector<PartLabel> truth = selection.dataset.labelsOf (id);
        const float scale = static_cast<float> (frame.prepared.stride), offset = static_cast<float> (frame.prepared.offset);
        for (auto &l : truth)
          l.tip_px = (l.tip_px - Eigen::Vector2f::Constant (offset)) / scale;
        writePng ((std::filesystem::path (overlay_dir) / (id + ".png")).string (),
                  renderPartLabels (frame.prepared.frame ? *frame.prepared.frame : *selection.dataset.loadFrame (id), labels,
                                    modes, truth));
      }
    }
    progress.step (i + 1);
  }
  nlohmann::json doc = evaluation.report ();
  doc["dataset"] = selection.dataset.directory ();
  doc["forest"] = loaded.forest_file;
  doc["forest_stride"] = loaded.forest_stride;
  doc["labels"] = selection.dataset.hasPartLabels () ? "exact (part-label images)" : "weak (from the tips and bases)";
  doc["labelling_ms_per_frame_median"] = medianMs (frame_ms);
  if (!json_path.empty ())
    writeJson (json_path, doc);
  std::printf ("%s: %d frames, %s labels; pixel accuracy %.3f, mean class recall %.3f\n",
               selection.dataset.directory ().c_str (), evaluation.frames (),
               selection.dataset.hasPartLabels () ? "exact" : "weak", evaluation.accuracy (),
               evaluation.meanClassRecall ());
  for (int p = 0; p < kLabelPartCount; ++p)
    std::printf ("  %-10s recall %.3f\n", labelPartName (p), evaluation.recall (p));
  return 0;
}
}  // namespace apps
}  // namespace agex
