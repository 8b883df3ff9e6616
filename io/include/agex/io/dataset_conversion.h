#pragma once
// Frame files (raw .u16 depth, .pcd clouds) turned into an unlabelled agex dataset
// (doc/dataset.md). A conversion is planned first and written second, so that a caller can
// check everything it reads (FrameFilesConversion::files) against the output path before
// a byte is written; the dataset itself is written atomically through DatasetWriter.

#include <agex/io/dataset.h>
#include <agex/io/frame_io.h>

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace agex
{
/** \brief The frame files under the inputs: each file as given, each directory's regular
  * files ending in extension (e.g. ".png"; not recursive), sorted by name per directory.
  * \throws std::runtime_error naming an input that does not exist, or when no file is found */
std::vector<std::string> collectFrameFiles (const std::vector<std::string> &inputs, const std::string &extension);

/** \brief The sequence of each file: the name of its directory, exactly (UTF-8). Two
  * different directories of one name would merge silently (a train and a test sequence),
  * and a name that cannot be a sequence name (validSequenceName) is refused rather than
  * changed. \throws std::runtime_error naming the directories */
std::vector<std::string> directorySequenceNames (const std::vector<std::string> &files);

/** A frame id made of a file name: every character but letters, digits, '-', '_' and '.'
  * becomes '_' (DatasetWriter's rule for ids). */
std::string frameIdFromName (std::string name);

/** A planned conversion of frame files of one format into a dataset. */
struct FrameFilesConversion
{
  std::string format;               ///< "u16" or "pcd", the files' extension
  std::vector<std::string> inputs;  ///< files and directories as given
  std::vector<std::string> files;   ///< the frame files found under them, in order
  /** Name, sensor, intrinsics, depth scale and provenance; the size is the first frame's. */
  DatasetInfo info;

  /** Everything the conversion reads: the inputs and the files (what no output may overwrite). */
  std::vector<std::string> inputFiles () const;
};

/** \brief Finds the frame files of format ("u16" or "pcd") under inputs and describes the
  * dataset: named name, sensor as given, the intrinsics of options, the depth scale of
  * options (0: 1 mm for u16; none for PCD, whose clouds are metres already), and the files
  * and inputs as provenance ("converted by agex_convert u16 from 3 file(s) under DIR").
  * \throws std::runtime_error as collectFrameFiles */
FrameFilesConversion planFrameFilesConversion (const std::string &format, const std::vector<std::string> &inputs,
                                               const std::string &name, const std::string &sensor,
                                               const FrameOptions &options);

/** \brief Writes the planned frames (loadFrame with options) as a dataset without labels:
  * each frame's sequence is its directory's name (directorySequenceNames), its id its file
  * name without the extension (frameIdFromName; "-2", "-3", ... added to repeats), and every
  * frame must have the first frame's size. progress (done, total) is called after each frame.
  * \return the frames written
  * \throws std::runtime_error naming the file of a bad frame or size; DatasetError as
  *         DatasetWriter (output exists and overwrite is false, or may not be replaced) */
std::size_t writeFrameFilesDataset (const FrameFilesConversion &conversion, const FrameOptions &options,
                                    const std::string &output, bool overwrite,
                                    const std::function<void (std::size_t, std::size_t)> &progress = {});
}  // namespace agex
