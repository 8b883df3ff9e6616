#include <agex/apps/detector_flags.h>

#include <boost/program_options.hpp>

#include <stdexcept>

namespace po = boost::program_options;

namespace agex
{
namespace apps
{
po::options_description
detectorOptionsDescription (DetectorChoice &choice, const std::string &model_default)
{
  choice.model = model_default;
  po::options_description desc ("Detector");
  desc.add_options ()
    ("model", po::value (&choice.model)->default_value (model_default),
     "model file: the classifier and the pipeline settings (default: the bundled model)")
    ("detector-mode", po::value (&choice.mode)->default_value (choice.mode),
     "agex: the model's classifier on AGEX points; forest: the per-pixel forest's part modes alone")
    ("forest", po::value (&choice.forest),
     "per-pixel body-part forest: an agex forest file, a PCL tree file (.txt, .txt.bz2) or a directory of them "
     "(e.g. ../shared/data/pcl_people)")
    ("forest-stride", po::value (&choice.forest_stride)->default_value (choice.forest_stride)->notifier ([] (int v) {
       if (v < 1 || v > 8)
         throw std::runtime_error ("--forest-stride must lie in [1, 8]");
     }),
     "forest: one evaluated pixel per stride x stride cell");
  return desc;
}

void
LoadedDetector::configure (BodyPartDetector<pcl::PointXYZ> &detector) const
{
  detector.setModel (model);
  detector.setForest (forest);
  detector.setMode (mode);
  detector.setForestStride (forest_stride);
}

LoadedDetector
loadDetector (const DetectorChoice &choice, DetectorKind kind)
{
  LoadedDetector loaded;
  if (!parseDetectorMode (choice.mode, loaded.mode))
    throw std::runtime_error ("unknown --detector-mode '" + choice.mode + "' (expected agex or forest)");
  if (loaded.mode == DetectorMode::Forest && choice.forest.empty ())
    throw std::runtime_error ("--detector-mode forest needs --forest (a forest file or a directory of PCL trees)");
  loaded.model = std::make_shared<const DetectorModel> (DetectorModel::load (choice.model));
  loaded.model->requireKind (kind, choice.model);
  loaded.files.push_back (choice.model);
  if (!choice.forest.empty ())
  {
    loaded.forest = BodyPartForest::load (choice.forest);
    loaded.files.push_back (choice.forest);
  }
  loaded.forest_stride = choice.forest_stride;
  return loaded;
}
}  // namespace apps
}  // namespace agex
