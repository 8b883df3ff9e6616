// agex_convert: turns recorded data into agex datasets (doc/dataset.md).
//   agex_convert bonn --input ../shared/data/bonn --output DIR [--view full|portrait] [--sequences 1,2]
//   agex_convert u16  --input FILE|DIR... --output DIR [--width W --height H]
//   agex_convert pcd  --input FILE|DIR... --output DIR

#include <agex/apps/command_line.h>
#include <agex/apps/output_guard.h>
#include <agex/apps/pipeline_flags.h>
#include <agex/detection/depth_pipeline.h>
#include <agex/io/bonn.h>
#include <agex/io/dataset.h>
#include <agex/io/frame_io.h>

#include <boost/program_options.hpp>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

namespace fs = std::filesystem;
namespace po = boost::program_options;

namespace
{
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

std::vector<std::string>
splitList (const std::string &text)
{
  std::vector<std::string> items;
  std::stringstream in (text);
  for (std::string item; std::getline (in, item, ',');)
    if (!item.empty ())
      items.push_back (item);
  return items;
}

/** Frame files under the inputs (files as given, directories scanned), sorted. */
std::vector<fs::path>
collectFiles (const std::vector<std::string> &inputs, const std::string &extension)
{
  std::vector<fs::path> files;
  for (const auto &input : inputs)
  {
    if (fs::is_directory (input))
    {
      std::vector<fs::path> found;
      for (const auto &entry : fs::directory_iterator (input))
        if (entry.is_regular_file () && entry.path ().extension () == extension)
          found.push_back (entry.path ());
      std::sort (found.begin (), found.end ());
      files.insert (files.end (), found.begin (), found.end ());
    }
    else if (fs::exists (input))
      files.emplace_back (input);
    else
      throw std::runtime_error (input + ": no such file or directory");
  }
  if (files.empty ())
    throw std::runtime_error ("no " + extension + " frames found in the inputs");
  return files;
}

std::string
sanitiseId (std::string id)
{
  for (char &c : id)
    if (!std::isalnum (static_cast<unsigned char> (c)) && c != '-' && c != '_' && c != '.')
      c = '_';
  return id;
}

/** The sequence of each file: the name of its directory, exactly (UTF-8). Two different
  * directories of one name would merge silently (a train and a test sequence), and a name
  * that cannot be a sequence name is refused rather than changed. */
std::vector<std::string>
sequenceNames (const std::vector<fs::path> &files)
{
  std::map<std::string, fs::path> directory_of;
  std::vector<std::string> names;
  for (const auto &file : files)
  {
    std::error_code ec;
    const fs::path dir = fs::weakly_canonical (fs::absolute (file, ec), ec).parent_path ();
    const std::string name = dir.filename ().string ();
    std::string why;
    if (!agex::validSequenceName (name, &why))
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

int
convertBonn (const std::string &input, const std::string &output, const std::string &view_name,
             const std::string &sequences_flag, const agex::FrameOptions &options, int label_radius,
             float depth_band, bool force)
{
  const fs::path root (input);
  const std::vector<agex::BonnLabel> rows = agex::readBonnLabels ((root / "labels.csv").string ());
  std::map<std::pair<std::string, std::string>, std::vector<agex::BonnLabel>> by_frame;
  for (const auto &row : rows)
    by_frame[{row.sequence, row.frame}].push_back (row);

  if (view_name != "full" && view_name != "portrait")
    throw std::runtime_error ("--view must be full or portrait, not '" + view_name + "'");
  const bool portrait = view_name == "portrait";
  const agex::FrameView view = agex::bonnPortraitView ();

  std::vector<std::string> sequences = splitList (sequences_flag);
  if (sequences.empty ())
    for (const auto &entry : fs::directory_iterator (root / "depth"))
      if (entry.is_directory ())
        sequences.push_back (entry.path ().filename ().string ());
  std::sort (sequences.begin (), sequences.end (), [] (const std::string &a, const std::string &b) {
    return a.size () != b.size () ? a.size () < b.size () : a < b;
  });

  std::vector<std::pair<std::string, fs::path>> frames;  // sequence, file
  for (const auto &sequence : sequences)
  {
    const fs::path dir = root / "depth" / sequence;
    if (!fs::is_directory (dir))
      throw std::runtime_error (dir.string () + ": no such sequence");
    for (const auto &file : collectFiles ({dir.string ()}, ".png"))
      frames.emplace_back (sequence, file);
  }

  agex::DatasetInfo info;
  info.name = std::string ("bonn-") + view_name;
  info.sensor = "kinect";
  info.intrinsics = portrait ? view.intrinsics (options.intrinsics) : options.intrinsics;
  info.width = portrait ? view.outputWidth () : 640;
  info.height = portrait ? view.outputHeight () : 480;
  const double scale = options.depth_scale > 0 ? options.depth_scale : 0.016;
  info.depth_scale = scale;
  std::ostringstream provenance;
  provenance << "Bonn body-part depth frames (" << input << ", BSD licence), sequences";
  for (const auto &s : sequences)
    provenance << " " << s;
  provenance << "; 8-bit depth x " << scale << " m; intrinsics fx=" << options.intrinsics.fx
             << " fy=" << options.intrinsics.fy << " cx=" << options.intrinsics.cx << " cy=" << options.intrinsics.cy
             << (portrait ? "; portrait view: crop x=140 y=20 360x440 scaled by 0.4 (nearest point)" : "")
             << "; label tips and bases lifted to 3D with the nearest foreground point within " << label_radius
             << " px (foreground: within " << depth_band << " m of the window's nearest depth)";
  info.provenance = provenance.str ();

  agex::FrameOptions frame_options = options;
  frame_options.depth_scale = scale;
  agex::InputFiles read ({input, (root / "labels.csv").string ()});
  for (const auto &frame : frames)
    read.add (frame.second.string ());
  agex::apps::checkOutputPath (output, agex::apps::OutputKind::Dataset, read, force);
  agex::DatasetWriter writer (output, info, force);
  std::size_t lifted = 0, unlifted = 0;
  agex::apps::Progress progress ("converted", frames.size ());
  for (std::size_t i = 0; i < frames.size (); ++i)
  {
    const auto &[sequence, file] = frames[i];
    const std::string frame_name = file.stem ().string ();
    const agex::Frame frame = agex::loadFrame (file.string (), frame_options);
    Cloud stored;
    if (portrait)
      agex::applyView (*frame.cloud, view, stored);
    else
      stored = *frame.cloud;

    std::vector<agex::PartLabel> labels;
    for (const auto &row : by_frame[{sequence, frame_name}])
    {
      agex::PartLabel label;
      label.part = row.part;
      label.instance = row.instance;
      label.keyframe = row.keyframe;
      // 3D from the full-resolution frame, whatever the stored view.
      const bool tip_ok = agex::liftPixelToSurface (*frame.cloud, row.tip_px.x (), row.tip_px.y (), label_radius,
                                                    depth_band, label.tip);
      const bool base_ok = agex::liftPixelToSurface (*frame.cloud, row.base_px.x (), row.base_px.y (),
                                                     label_radius, depth_band, label.base);
      if (!tip_ok)
        label.tip.setConstant (std::numeric_limits<float>::quiet_NaN ());
      if (!base_ok)
        label.base.setConstant (std::numeric_limits<float>::quiet_NaN ());
      // Without a 3D tip a label cannot be scored; it stays in the file, marked invisible.
      label.visible = tip_ok;
      tip_ok ? ++lifted : ++unlifted;
      auto to_view = [&] (const Eigen::Vector2f &p) {
        if (!portrait)
          return p;
        const cv::Point2f q = view.toView (cv::Point2f (p.x (), p.y ()));
        return Eigen::Vector2f (q.x, q.y);
      };
      label.tip_px = to_view (row.tip_px);
      label.base_px = to_view (row.base_px);
      labels.push_back (label);
    }
    writer.addFrame (sequence + "_" + frame_name, sequence, stored, labels);
    progress.step (i + 1);
  }
  writer.commit ();
  std::cout << output << ": " << frames.size () << " frames, " << lifted << " labels lifted to 3D, " << unlifted
            << " without depth near the labelled pixel (marked invisible)\n";
  return 0;
}

int
convertFrames (const std::string &kind, const std::vector<std::string> &inputs, const std::string &output,
               const agex::FrameOptions &options, const std::string &sensor, bool force)
{
  const std::vector<fs::path> files = collectFiles (inputs, "." + kind);
  agex::InputFiles read (inputs);
  for (const auto &file : files)
    read.add (file.string ());
  agex::apps::checkOutputPath (output, agex::apps::OutputKind::Dataset, read, force);
  const std::vector<std::string> sequences = sequenceNames (files);
  agex::DatasetInfo info;
  info.name = output.empty () ? kind : fs::path (output).filename ().string ();
  info.sensor = sensor;
  info.intrinsics = options.intrinsics;
  info.depth_scale = kind == "u16" ? (options.depth_scale > 0 ? options.depth_scale : 0.001) : 0.0;
  std::ostringstream provenance;
  provenance << "converted by agex_convert " << kind << " from " << files.size () << " file(s) under";
  for (const auto &in : inputs)
    provenance << " " << in;
  info.provenance = provenance.str ();

  std::unique_ptr<agex::DatasetWriter> writer;
  std::set<std::string> ids;
  agex::apps::Progress progress ("converted", files.size ());
  for (std::size_t i = 0; i < files.size (); ++i)
  {
    const agex::Frame frame = agex::loadFrame (files[i].string (), options);
    if (!writer)
    {
      info.width = static_cast<int> (frame.cloud->width);
      info.height = static_cast<int> (frame.cloud->height);
      writer = std::make_unique<agex::DatasetWriter> (output, info, force);
    }
    else if (static_cast<int> (frame.cloud->width) != info.width || static_cast<int> (frame.cloud->height) != info.height)
      throw std::runtime_error (files[i].string () + ": is " + std::to_string (frame.cloud->width) + "x" +
                                std::to_string (frame.cloud->height) + ", unlike the first frame (" +
                                std::to_string (info.width) + "x" + std::to_string (info.height) +
                                "); a dataset holds one frame size");
    std::string id = sanitiseId (files[i].stem ().string ());
    for (int n = 2; ids.count (id); ++n)
      id = sanitiseId (files[i].stem ().string ()) + "-" + std::to_string (n);
    ids.insert (id);
    writer->addFrame (id, sequences[i], *frame.cloud, {});
    progress.step (i + 1);
  }
  writer->commit ();
  std::cout << output << ": " << files.size () << " frames (no labels)\n";
  return 0;
}
}  // namespace

int
main (int argc, char **argv)
{
  agex::FrameOptions frame_options;
  std::string mode, output, view = "portrait", sequences, sensor = "kinect";
  std::vector<std::string> inputs;
  int label_radius = 6;
  float depth_band = 0.05f;
  bool force = false;

  po::options_description general ("agex_convert bonn|u16|pcd --input PATH... --output DIR [options]\n"
                                    "Converts recorded frames into an agex dataset (doc/dataset.md)");
  general.add_options () ("help,h", "show this help") ("mode", po::value (&mode), "bonn, u16 or pcd")
    ("input", po::value (&inputs)->multitoken (), "bonn: the Bonn data directory; u16/pcd: files or directories")
    ("output", po::value (&output), "dataset directory to create")
    ("force", po::bool_switch (&force), "replace an existing output dataset")
    ("view", po::value (&view)->default_value (view), "bonn: portrait (144x176, as the source) or full (640x480)")
    ("sequences", po::value (&sequences), "bonn: comma-separated sequences (default: all)")
    ("label-radius", po::value (&label_radius)->default_value (label_radius),
     "bonn: pixels searched around a label for its surface point")
    ("label-depth-band", po::value (&depth_band)->default_value (depth_band, "0.05"),
     "bonn: metres behind the nearest depth in that window still counted as foreground")
    ("sensor", po::value (&sensor)->default_value (sensor), "u16/pcd: sensor name recorded in dataset.json");
  po::options_description all;
  all.add (general).add (agex::apps::frameOptionsDescription (frame_options));
  po::positional_options_description positional;
  positional.add ("mode", 1);

  try
  {
    if (!agex::apps::parseCommandLine (argc, argv, all, positional))
      return 0;
    if (output.empty () || inputs.empty ())
      throw std::runtime_error ("--input and --output are required (see --help)");
    if (label_radius < 0 || !(depth_band > 0.f))
      throw std::runtime_error ("--label-radius must be >= 0 and --label-depth-band > 0");
    if (mode == "bonn")
    {
      if (inputs.size () != 1)
        throw std::runtime_error ("bonn takes one --input: the Bonn data directory");
      return convertBonn (inputs[0], output, view, sequences, frame_options, label_radius, depth_band, force);
    }
    if (mode == "u16" || mode == "pcd")
      return convertFrames (mode, inputs, output, frame_options, sensor, force);
    throw std::runtime_error ("unknown mode '" + mode + "' (expected bonn, u16 or pcd)");
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_convert: error: " << e.what () << "\n";
    return 1;
  }
}
