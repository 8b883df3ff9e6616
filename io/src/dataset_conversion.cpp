#include <agex/io/dataset_conversion.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>

namespace fs = std::filesystem;

namespace agex
{
std::vector<std::string>
collectFrameFiles (const std::vector<std::string> &inputs, const std::string &extension)
{
  std::vector<std::string> files;
  for (const auto &input : inputs)
  {
    if (fs::is_directory (input))
    {
      std::vector<fs::path> found;
      for (const auto &entry : fs::directory_iterator (input))
        if (entry.is_regular_file () && entry.path ().extension () == extension)
          found.push_back (entry.path ());
      std::sort (found.begin (), found.end ());
      for (const auto &path : found)
        files.push_back (path.string ());
    }
    else if (fs::exists (input))
      files.push_back (input);
    else
      throw std::runtime_error (input + ": no such file or directory");
  }
  if (files.empty ())
    throw std::runtime_error ("no " + extension + " frames found in the inputs");
  return files;
}

std::vector<std::string>
directorySequenceNames (const std::vector<std::string> &files)
{
  std::map<std::string, fs::path> directory_of;
  std::vector<std::string> names;
  for (const auto &file : files)
  {
    std::error_code ec;
    const fs::path dir = fs::weakly_canonical (fs::absolute (file, ec), ec).parent_path ();
    const std::string name = dir.filename ().string ();
    std::string why;
    if (!validSequenceName (name, &why))
      throw std::runtime_error (dir.string () + ": the directory name " + why +
                                "; it would be the frames' sequence name: rename the directory");
    const auto [it, inserted] = directory_of.emplace (name, dir);
    if (!inserted && it->second != dir)
      throw std::runtime_error (it->second.string () + " and " + dir.string () + " would both be sequence '" + name +
                                "'; convert them into separate datasets or rename one");
    names.push_back (name);
  }
  return names;
}

std::string
frameIdFromName (std::string name)
{
  for (char &c : name)
    if (!std::isalnum (static_cast<unsigned char> (c)) && c != '-' && c != '_' && c != '.')
      c = '_';
  return name;
}

std::vector<std::string>
FrameFilesConversion::inputFiles () const
{
  std::vector<std::string> read = inputs;
  read.insert (read.end (), files.begin (), files.end ());
  return read;
}

FrameFilesConversion
planFrameFilesConversion (const std::string &format, const std::vector<std::string> &inputs, const std::string &name,
                          const std::string &sensor, const FrameOptions &options)
{
  FrameFilesConversion conversion;
  conversion.format = format;
  conversion.inputs = inputs;
  conversion.files = collectFrameFiles (inputs, "." + format);
  DatasetInfo &info = conversion.info;
  info.name = name;
  info.sensor = sensor;
  info.intrinsics = options.intrinsics;
  info.depth_scale = format == "u16" ? (options.depth_scale > 0 ? options.depth_scale : 0.001) : 0.0;
  std::ostringstream provenance;
  provenance << "converted by agex_convert " << format << " from " << conversion.files.size () << " file(s) under";
  for (const auto &in : inputs)
    provenance << " " << in;
  info.provenance = provenance.str ();
  return conversion;
}

std::size_t
writeFrameFilesDataset (const FrameFilesConversion &conversion, const FrameOptions &options,
                        const std::string &output, bool overwrite,
                        const std::function<void (std::size_t, std::size_t)> &progress)
{
  const std::vector<std::string> &files = conversion.files;
  const std::vector<std::string> sequences = directorySequenceNames (files);
  DatasetInfo info = conversion.info;
  std::unique_ptr<DatasetWriter> writer;
  std::set<std::string> ids;
  for (std::size_t i = 0; i < files.size (); ++i)
  {
    const Frame frame = loadFrame (files[i], options);
    if (!writer)
    {
      info.width = static_cast<int> (frame.cloud->width);
      info.height = static_cast<int> (frame.cloud->height);
      writer = std::make_unique<DatasetWriter> (output, info, overwrite);
    }
    else if (static_cast<int> (frame.cloud->width) != info.width || static_cast<int> (frame.cloud->height) != info.height)
      throw std::runtime_error (files[i] + ": is " + std::to_string (frame.cloud->width) + "x" +
                                std::to_string (frame.cloud->height) + ", unlike the first frame (" +
                                std::to_string (info.width) + "x" + std::to_string (info.height) +
                                "); a dataset holds one frame size");
    const std::string stem = fs::path (files[i]).stem ().string ();
    std::string id = frameIdFromName (stem);
    for (int n = 2; ids.count (id); ++n)
      id = frameIdFromName (stem) + "-" + std::to_string (n);
    ids.insert (id);
    writer->addFrame (id, sequences[i], *frame.cloud, {});
    if (progress)
      progress (i + 1, files.size ());
  }
  writer->commit ();
  return files.size ();
}
}  // namespace agex
