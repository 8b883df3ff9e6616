#pragma once
// "--dataset DIR[@SEQ,SEQ,...]": a dataset directory, optionally restricted to some
// of its sequences (split train and test data by sequence, never by frame).

#include <agex/io/dataset.h>

#include <string>
#include <vector>

namespace agex
{
namespace apps
{
struct DatasetSelection
{
  Dataset dataset;
  std::vector<std::string> frame_ids;  ///< selected frames, in dataset order
};

/** \brief Reads "DIR" or "DIR@1,2,3"; keyframes_only keeps frames with a keyframe label.
  * \throws DatasetError (bad dataset) or std::runtime_error (unknown sequence) */
DatasetSelection selectDataset (const std::string &spec, bool keyframes_only);

/** Every file of a dataset (dataset.json, labels.csv, all its frames and their part-label and
  * person images): what no output may overwrite. */
std::vector<std::string> datasetFiles (const Dataset &dataset);
}  // namespace apps
}  // namespace agex
