#pragma once
// Reading the Bonn body-part data (../shared/data/bonn): depth PNGs per sequence
// and labels.csv with head, hand and foot tips and bases in 640x480 pixels; and turning it
// into an agex dataset (agex_convert bonn), planned first so that a caller can check what it
// reads against the output before anything is written.

#include <agex/io/dataset.h>
#include <agex/io/frame_io.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>

#include <cstddef>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace agex
{
/** One row of the Bonn labels.csv (sequence,frame,keyframe,part,instance,tip_u,tip_v,base_u,base_v). */
struct BonnLabel
{
  std::string sequence;
  std::string frame;  ///< as in the file name, e.g. "002"
  bool keyframe = false;
  BodyPart part = BodyPart::Head;
  int instance = 0;
  Eigen::Vector2f tip_px = Eigen::Vector2f::Zero ();
  Eigen::Vector2f base_px = Eigen::Vector2f::Zero ();
};

/** \brief Reads and validates the Bonn labels.csv. \throws DatasetError naming path:line */
std::vector<BonnLabel> readBonnLabels (const std::string &path);

/** \brief The 3D surface point standing for a labelled pixel.
  *
  * Tips are often labelled on a silhouette's edge, where the pixel itself may be
  * background or have no depth. Among the finite points within radius pixels of
  * (u, v) we keep the foreground: those at most depth_band metres behind the
  * nearest of them; the one closest to (u, v) in the image wins (ties: the lower
  * index). Returns false when the window holds no finite point.
  * \param[out] pixel the chosen pixel (u, v), if not null */
bool liftPixelToSurface (const pcl::PointCloud<pcl::PointXYZ> &cloud, float u, float v, int radius,
                         float depth_band, Eigen::Vector3f &point, Eigen::Vector2i *pixel = nullptr);

/** How the Bonn data becomes an agex dataset. */
struct BonnConversionParams
{
  /** Store the 144x176 portrait view the source worked on (bonnPortraitView) rather than the
    * 640x480 frames; the labels are lifted to 3D from the full frame either way. */
  bool portrait = true;
  /** Sequences (directories under depth/); empty: all of them. */
  std::vector<std::string> sequences;
  /** The frames' intrinsics and depth scale (0: 0.016 m per 8-bit step, the Bonn frames'). */
  FrameOptions frame_options;
  /** liftPixelToSurface's search: pixels around a labelled pixel, and metres behind the
    * window's nearest depth still counted as foreground. */
  int label_radius = 6;
  float depth_band = 0.05f;
};

/** A planned conversion of the Bonn data: what it reads and the dataset it describes. */
struct BonnConversion
{
  std::string root;  ///< the Bonn data directory (depth/, labels.csv)
  BonnConversionParams params;  ///< sequences listed and sorted (1, 2, ..., 10: by length, then name)
  std::vector<BonnLabel> labels;
  std::vector<std::pair<std::string, std::string>> frames;  ///< (sequence, depth PNG), in order
  DatasetInfo info;  ///< name bonn-portrait or bonn-full, size, intrinsics, depth scale, provenance

  /** Everything the conversion reads: root, its labels.csv and the frames' PNGs (what no
    * output may overwrite). */
  std::vector<std::string> inputFiles () const;
};

/** \brief Reads root/labels.csv and lists the depth PNGs of the sequences.
  * \throws DatasetError (labels.csv), std::runtime_error naming a missing sequence or one
  *         without frames */
BonnConversion planBonnConversion (const std::string &root, const BonnConversionParams &params);

/** What writeBonnDataset did. */
struct BonnConversionStats
{
  std::size_t frames = 0;
  std::size_t lifted = 0;    ///< labels lifted to 3D
  std::size_t unlifted = 0;  ///< labels without depth near their pixel: kept, marked invisible
};

/** \brief Writes the planned frames and their labels as an agex dataset: each frame (id
  * "<sequence>_<frame>") stored full or in the portrait view, each label's tip and base lifted
  * to 3D from the full frame (liftPixelToSurface; NaN where the window holds no depth, and a
  * label without a 3D tip stays in the file, invisible) and its pixels moved into the stored
  * view. progress (done, total) is called after each frame.
  * \throws FrameError naming a bad frame; DatasetError as DatasetWriter */
BonnConversionStats writeBonnDataset (const BonnConversion &conversion, const std::string &output, bool overwrite,
                                      const std::function<void (std::size_t, std::size_t)> &progress = {});
}  // namespace agex
