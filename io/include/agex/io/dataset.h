#pragma once
// The agex dataset format (doc/dataset.md): a directory with
//   dataset.json      name, sensor, size, intrinsics, depth scale, units, provenance,
//                     and the frames in order with the sequence each belongs to
//   frames/<id>.pcd   organized pcl::PointXYZ, metres, NaN = invalid
//   labels.csv        one row per labelled part instance per frame
//   labels/<id>.png   optional: per-pixel part ids (8-bit, the frame's size), named in
//                     dataset.json's "part_labels"
//   persons/<id>.png  optional: per-pixel person ids (8-bit; 0 none, k = person k)
// Readers validate everything and name the file (and line) of any error. Writers
// build the dataset in a temporary directory beside the target and rename it into
// place, so an interrupted run leaves no half dataset behind.

#include <agex/common/body_part.h>
#include <agex/io/frame_io.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <opencv2/core/mat.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace agex
{
/** One labelled part instance in one frame. */
struct PartLabel
{
  std::string frame;  ///< frame id
  BodyPart part = BodyPart::Head;
  int instance = 0;
  Eigen::Vector3f tip = Eigen::Vector3f::Zero ();   ///< metres, camera frame (NaN if unknown)
  Eigen::Vector3f base = Eigen::Vector3f::Zero ();  ///< metres, camera frame (NaN if unknown)
  Eigen::Vector2f tip_px = Eigen::Vector2f::Zero ();   ///< pixel (u, v) in the stored frame
  Eigen::Vector2f base_px = Eigen::Vector2f::Zero ();  ///< pixel (u, v) in the stored frame
  bool visible = true;
  bool keyframe = false;
  /** Which person of the frame (1, 2, ...; the value of the person image); 1 in files
    * without a person column. */
  int person = 1;
};

struct DatasetInfo
{
  std::string name;
  std::string sensor;  ///< e.g. "kinect", "sr4000", "bonn-kinect"
  int width = 0, height = 0;
  CameraIntrinsics intrinsics;
  double depth_scale = 0.0;   ///< metres per unit of the source depth (informative)
  std::string units = "m";    ///< units of the stored clouds; always metres
  std::string provenance;     ///< where the frames and labels came from, how converted
  /** Per-pixel part ids (1-255) and their names; empty: no part-label images. */
  std::map<int, std::string> part_labels;
  /** True if every frame has a person image (persons/<id>.png). */
  bool person_labels = false;
};

struct DatasetFrame
{
  std::string id;
  std::string sequence;
};

/** A dataset problem: the message names the file (and line) and what is wrong. */
class DatasetError : public std::runtime_error
{
public:
  using std::runtime_error::runtime_error;
};

class Dataset
{
public:
  /** \brief Reads and validates a dataset directory (not the frame clouds: see loadFrame).
    * \throws DatasetError */
  static Dataset read (const std::string &directory);

  const std::string &directory () const { return directory_; }
  const DatasetInfo &info () const { return info_; }
  const std::vector<DatasetFrame> &frames () const { return frames_; }
  const std::vector<PartLabel> &labels () const { return labels_; }

  /** Labels of one frame (empty if it has none). */
  std::vector<PartLabel> labelsOf (const std::string &frame_id) const;
  /** True if any label of the frame is a keyframe label. */
  bool isKeyframe (const std::string &frame_id) const;
  std::string framePath (const std::string &frame_id) const;
  /** \brief Loads a frame's organized cloud. \throws FrameError naming the file */
  pcl::PointCloud<pcl::PointXYZ>::Ptr loadFrame (const std::string &frame_id) const;

  /** True if every frame has a part-label image (dataset.json lists "part_labels"). */
  bool hasPartLabels () const { return !info_.part_labels.empty (); }
  /** labels/<id>.png */
  std::string partLabelPath (const std::string &frame_id) const;
  /** \brief A frame's part-label image: CV_8UC1 of the dataset's size, each pixel 0 (not
    * a body) or an id of info ().part_labels. \throws DatasetError naming the file if
    * the dataset has none, or the image cannot be decoded, is not 8-bit single-channel,
    * has another size or holds an id that dataset.json does not name */
  cv::Mat loadPartLabels (const std::string &frame_id) const;
  /** True if every frame has a person image (dataset.json: "person_labels": true). */
  bool hasPersonLabels () const { return info_.person_labels; }
  /** persons/<id>.png */
  std::string personLabelPath (const std::string &frame_id) const;
  /** \brief A frame's person image: CV_8UC1 of the dataset's size, 0 where no person, k
    * where person k (labels.csv's person). \throws DatasetError as loadPartLabels */
  cv::Mat loadPersonLabels (const std::string &frame_id) const;

private:
  std::string directory_;
  DatasetInfo info_;
  std::vector<DatasetFrame> frames_;
  std::vector<PartLabel> labels_;
  std::map<std::string, std::vector<std::size_t>> labels_by_frame_;
};

/** \brief Reads labels.csv. \throws DatasetError naming path:line */
std::vector<PartLabel> readLabelsCsv (const std::string &path);
/** Formats labels as labels.csv text (header included). */
std::string formatLabelsCsv (const std::vector<PartLabel> &labels);

/** \brief Why the existing path may not be replaced by a new dataset (DatasetWriter with
  * overwrite, agex_convert and agex_synth --force): "" if it is an agex dataset directory (its
  * dataset.json says format agex-dataset) holding nothing but what DatasetWriter writes
  * (dataset.json, labels.csv, frames/ with .pcd files, labels/ and persons/ with .png files),
  * else what it is, e.g. "is a regular
  * file, not an agex dataset" or "holds notes.txt, which is not part of an agex dataset".
  * Recognised by content, never by name. */
std::string datasetReplaceProblem (const std::string &path);

/** The agex dataset directory a file belongs to (dataset.json, labels.csv, frames/<id>.pcd,
  * labels/<id>.png or persons/<id>.png of a directory whose dataset.json says format
  * agex-dataset), or "". */
std::string enclosingDataset (const std::string &file);

/** \brief Whether name can be a sequence name as it is: valid UTF-8 without
  * control characters, ',' or '@' (they separate sequences in "DIR@SEQ,SEQ"). why gets the
  * reason if not. An empty name is allowed (frames without a sequence). */
bool validSequenceName (const std::string &name, std::string *why = nullptr);

/** \brief Writes a dataset atomically: frames and labels go to a temporary directory
  * next to the target, which commit() renames into place. Without commit() (an
  * exception, an interrupted run) the temporary directory is removed. */
class DatasetWriter
{
public:
  /** \throws DatasetError if directory exists and overwrite is false, or if overwrite is true
    * and what is there may not be replaced (datasetReplaceProblem: only an earlier agex
    * dataset, never a file or a directory of other things) */
  DatasetWriter (const std::string &directory, const DatasetInfo &info, bool overwrite = false);
  ~DatasetWriter ();
  DatasetWriter (const DatasetWriter &) = delete;
  DatasetWriter &operator= (const DatasetWriter &) = delete;

  /** Adds a frame (organized cloud, metres) and its labels; ids must be unique and
    * made of letters, digits, '_', '-' and '.', the sequence a validSequenceName, and each
    * visible label needs a finite tip. */
  void addFrame (const std::string &id, const std::string &sequence, const pcl::PointCloud<pcl::PointXYZ> &cloud,
                 const std::vector<PartLabel> &labels);
  /** The same with colour (an RGB-D frame): readers take x, y, z; agex_annotate rgbd the colour. */
  void addFrame (const std::string &id, const std::string &sequence, const pcl::PointCloud<pcl::PointXYZRGBA> &cloud,
                 const std::vector<PartLabel> &labels);
  /** Adds the part-label image of a frame added before: CV_8UC1 of the dataset's size,
    * each pixel 0 or an id of info.part_labels. Once one frame has one, every frame
    * needs one (commit checks). */
  void addPartLabels (const std::string &id, const cv::Mat &labels);
  /** Adds the person image of a frame added before: CV_8UC1 of the dataset's size, 0 =
    * no person, k = the labels of person k. Once one frame has one, every frame needs one. */
  void addPersonLabels (const std::string &id, const cv::Mat &persons);
  /** Writes dataset.json and labels.csv and moves the dataset into place. */
  void commit ();

private:
  std::string directory_, staging_;
  DatasetInfo info_;
  bool overwrite_ = false, committed_ = false;
  std::vector<DatasetFrame> frames_;
  std::vector<PartLabel> labels_;

  /** Checks id and size; returns the frame's path in the staging directory. */
  std::string framePath (const std::string &id, std::uint32_t width, std::uint32_t height) const;
  void checkLabels (const std::string &id, const std::vector<PartLabel> &labels) const;
  void addLabels (const std::string &id, const std::string &sequence, const std::vector<PartLabel> &labels);
  void addImage (const std::string &id, const cv::Mat &image, const char *folder, const char *what,
                 std::set<std::string> &added);
  std::set<std::string> part_label_ids_, person_ids_;
};
}  // namespace agex
