#include <agex/detection/part_label_training.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace agex
{
namespace
{
bool
endsWith (const std::string &text, const std::string &end)
{
  return text.size () >= end.size () && text.compare (text.size () - end.size (), end.size (), end) == 0;
}

/** Exact classes from the frame's part-label image, on the filtered frame's finite pixels. */
bool
exactClasses (const Dataset &dataset, const std::string &id, PartLabelledFrame &out)
{
  const cv::Mat image = dataset.loadPartLabels (id);
  const auto &cloud = *out.prepared.filtered;
  if (image.cols != static_cast<int> (out.prepared.input_width) || image.rows != static_cast<int> (out.prepared.input_height))
    throw DatasetError (dataset.partLabelPath (id) + ": not of the frame's size");
  std::map<int, int> parts;
  for (const auto &[label_id, name] : dataset.info ().part_labels)
    parts[label_id] = labelPartOfName (name);
  // The filtered frame may sample the input (DepthPipelineParams::working_spacing).
  for (int v = 0; v < static_cast<int> (cloud.height); ++v)
    for (int u = 0; u < static_cast<int> (cloud.width); ++u)
    {
      const int index = v * static_cast<int> (cloud.width) + u;
      const Eigen::Vector2i pixel = out.prepared.inputPixel (index);
      const int label_id = image.at<std::uint8_t> (pixel.y (), pixel.x ());
      if (label_id == 0 || !std::isfinite (cloud[static_cast<std::size_t> (index)].z))
        continue;
      const auto it = parts.find (label_id);
      out.body.push_back (index);
      out.classes.push_back (it == parts.end () ? -1 : it->second);
    }
  out.exact = true;
  return !out.body.empty ();
}

/** Weak classes of the meshes' pixels from the labelled tips and bases. */
bool
weakClasses (const std::vector<PartLabel> &labels, const WeakPartLabelParams &weak, PartLabelledFrame &out)
{
  if (labels.empty ())
    return false;
  for (const auto &l : labels)
    if (!l.visible || !l.tip.allFinite () || !l.base.allFinite ())
      return false;  // a part we cannot place would be labelled "other body"
  for (const int i : out.prepared.meshIndices ())
    out.body.push_back (i);
  std::sort (out.body.begin (), out.body.end ());
  out.body.erase (std::unique (out.body.begin (), out.body.end ()), out.body.end ());
  const auto &cloud = *out.prepared.filtered;
  for (const auto i : out.body)
  {
    const Eigen::Vector3f p = cloud[static_cast<std::size_t> (i)].getVector3fMap ();
    int cls = kLabelOtherBody;
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
}  // namespace

void
WeakPartLabelParams::validate () const
{
  for (int p = 0; p < 3; ++p)
    if (!(reach[p] > 0.f && reach[p] <= 1.f) || !(radius[p] > 0.f && radius[p] <= 1.f))
      throw std::invalid_argument ("weak-label reaches and radii must lie in (0, 1] metres");
  if (!(beyond_tip >= 0.f && beyond_tip <= 0.2f))
    throw std::invalid_argument ("the weak labels' beyond-tip margin must lie in [0, 0.2] metres");
}

int
labelPartOfName (const std::string &name)
{
  if (name == "head")
    return kLabelHead;
  if (endsWith (name, "hand"))
    return kLabelHand;
  if (endsWith (name, "foot"))
    return kLabelFoot;
  if (name == "body")
    return kLabelNone;
  return kLabelOtherBody;
}

bool
partLabelledFrame (const Dataset &dataset, const std::string &id, const DepthPipelineParams &params,
                   const WeakPartLabelParams &weak, bool raw_depth, PartLabelledFrame &out)
{
  out = PartLabelledFrame ();
  out.id = id;
  const auto cloud = dataset.loadFrame (id);
  out.prepared = runDepthPipeline (cloud, params);
  if (!out.prepared.filtered)
    return false;
  const bool found = dataset.hasPartLabels () ? exactClasses (dataset, id, out)
                                              : weakClasses (dataset.labelsOf (id), weak, out);
  const pcl::PointCloud<pcl::PointXYZ>::ConstPtr raw = out.prepared.frame ? out.prepared.frame : cloud;
  out.cloud = raw_depth ? raw : out.prepared.filtered;
  return found;
}

void
PartLabelEvaluation::addFrame (const PartLabelledFrame &frame, const pcl::PointCloud<BodyPartLabelPoint> &labels)
{
  ++frames_;
  for (std::size_t j = 0; j < frame.body.size () && j < frame.classes.size (); ++j)
  {
    const int truth = frame.classes[j];
    const auto index = static_cast<std::size_t> (frame.body[j]);
    if (truth < 0 || truth >= kLabelPartCount || index >= labels.size ())
      continue;
    const int got = labels[index].label;
    ++confusion_[static_cast<std::size_t> (truth)][got < 0 || got >= kLabelPartCount ? 4 : got];
  }
}

double
PartLabelEvaluation::accuracy () const
{
  std::size_t total = 0, correct = 0;
  for (int t = 0; t < kLabelPartCount; ++t)
    for (int g = 0; g < 5; ++g)
    {
      total += confusion_[t][g];
      correct += t == g ? confusion_[t][g] : 0;
    }
  return total ? static_cast<double> (correct) / total : std::nan ("");
}

double
PartLabelEvaluation::recall (int part) const
{
  std::size_t row = 0;
  for (int g = 0; g < 5; ++g)
    row += confusion_[part][g];
  return row ? static_cast<double> (confusion_[part][part]) / row : std::nan ("");
}

double
PartLabelEvaluation::meanClassRecall () const
{
  double sum = 0.0;
  int n = 0;
  for (int p = 0; p < kLabelPartCount; ++p)
    if (std::isfinite (recall (p)))
      sum += recall (p), ++n;
  return n ? sum / n : std::nan ("");
}

nlohmann::json
PartLabelEvaluation::report () const
{
  auto number = [] (double v) { return std::isfinite (v) ? nlohmann::json (v) : nlohmann::json (nullptr); };
  nlohmann::json doc;
  doc["frames"] = frames_;
  doc["pixel_accuracy"] = number (accuracy ());
  doc["mean_class_recall"] = number (meanClassRecall ());
  const char *columns[] = {"head", "hand", "foot", "other_body", "none"};
  for (int t = 0; t < kLabelPartCount; ++t)
  {
    doc["recall"][labelPartName (t)] = number (recall (t));
    for (int g = 0; g < 5; ++g)
      doc["confusion"][labelPartName (t)][columns[g]] = confusion_[t][g];
  }
  doc["confusion_rows"] = "truth (the frame's classes); columns: the forest's winning part, none where unlabelled";
  return doc;
}
}  // namespace agex
