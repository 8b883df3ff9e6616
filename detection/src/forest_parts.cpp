#include <agex/detection/forest_parts.h>

#include <agex/classification/body_part_labeling.h>
#include <agex/detection/fused_candidates.h>

#include <chrono>
#include <stdexcept>

namespace agex
{
const char *
forestInputName (ForestInput input)
{
  return input == ForestInput::Automatic ? "automatic" : input == ForestInput::Persons ? "persons" : "meshes";
}

bool
parseForestInput (const std::string &name, ForestInput &input)
{
  if (name == "automatic")
    input = ForestInput::Automatic;
  else if (name == "persons")
    input = ForestInput::Persons;
  else if (name == "meshes")
    input = ForestInput::Meshes;
  else
    return false;
  return true;
}

const char *
partProposalsName (PartProposals proposals)
{
  return proposals == PartProposals::Blobs ? "blobs" : "modes";
}

bool
parsePartProposals (const std::string &name, PartProposals &proposals)
{
  if (name == "blobs")
    proposals = PartProposals::Blobs;
  else if (name == "modes")
    proposals = PartProposals::Modes;
  else
    return false;
  return true;
}

void
ForestPartSettings::validate (const std::function<std::string (const std::string &key)> &name) const
{
  if (input != ForestInput::Automatic && input != ForestInput::Persons && input != ForestInput::Meshes)
    throw std::invalid_argument (name ("input") + " is not automatic, persons or meshes");
  if (proposals != PartProposals::Blobs && proposals != PartProposals::Modes)
    throw std::invalid_argument (name ("proposals") + " is neither blobs nor modes");
  if (!(floor_margin >= 0.f && floor_margin <= 0.5f))
    throw std::invalid_argument (name ("floor_margin") + " is " + std::to_string (floor_margin) +
                                 ", outside [0, 0.5] metres");
  blobs.validate ([&] (const std::string &key) { return name ("blobs." + key); });
}

bool
forestParts (const DepthPipelineResult &prepared, const pcl::PointCloud<pcl::PointXYZ>::ConstPtr &frame,
             const BodyPartForest::ConstPtr &forest, float fx, float fy, int stride,
             const ForestPartSettings &settings, pcl::PointCloud<BodyPartLabelPoint> &labels,
             std::vector<PartMode> &parts, std::pair<double, double> *ms)
{
  // The behaviour before the persons and blobs: kept as it is, the fused model's.
  // Measured on Bonn (doc/forest.md): PCL's forests lose the hands on the cleaned meshes and
  // read a thinned head as a hand; ours, trained on the meshes, do best on them.
  const ForestInput input = settings.input != ForestInput::Automatic ? settings.input
                            : forest && forest->numClasses () == BodyPartForest::kPclLabelCount ? ForestInput::Persons
                                                                                                  : ForestInput::Meshes;
  const bool persons = input == ForestInput::Persons && frame && !prepared.persons.empty () &&
                       frame->width == (prepared.filtered ? prepared.filtered->width : 0u) &&
                       frame->height == (prepared.filtered ? prepared.filtered->height : 0u);
  if (!persons && settings.proposals == PartProposals::Modes)
    return labelPersonParts (prepared, forest, fx, fy, stride, labels, parts, ms);

  const auto start = std::chrono::steady_clock::now ();
  labels.clear ();
  parts.clear ();
  if (!forest || !prepared.filtered || !(fx > 0.f) || !(fy > 0.f))
    return false;
  // The person as segmented: the mixed-pixel, median and spur filters thin a forearm or a
  // hand at 2 m to nothing or to a sliver the forest has never seen (a narrowed head reads
  // as a hand), so the forest reads the frame's own depth at every pixel of the person.
  // Persons too far for a hand to be found are labelled too: the detector drops their hand
  // guesses only (PersonInfo::too_far).
  auto body = std::make_shared<pcl::Indices> ();
  if (persons)
  {
    for (std::size_t p = 0; p < prepared.persons.size (); ++p)
    {
      for (const auto i : prepared.persons[p].indices)
      {
        if (i < 0 || static_cast<std::size_t> (i) >= frame->size ())
          continue;
        const Eigen::Vector3f x = (*frame)[static_cast<std::size_t> (i)].getVector3fMap ();
        if (prepared.floor_found && x.allFinite () &&
            prepared.floor_plane.head<3> ().dot (x) + prepared.floor_plane[3] < settings.floor_margin)
          continue;
        body->push_back (i);
      }
    }
  }
  else
  {
    const std::vector<int> meshes = prepared.meshIndices ();
    body->assign (meshes.begin (), meshes.end ());
  }
  if (body->empty ())
    return false;
  if (!labelBodyPixels (persons ? frame : prepared.filtered, body, forest, fx, fy, stride, labels))
    return false;
  const auto labelled = std::chrono::steady_clock::now ();
  bool found = false;
  if (settings.proposals == PartProposals::Blobs)
  {
    PartBlobParams params = settings.blobs;
    params.fx = fx;
    params.fy = fy;
    PartBlobEstimation estimation;
    estimation.setParams (params);
    found = estimation.compute (labels, *body, parts);
  }
  else
  {
    PartModeParams params;
    params.fx = fx;
    params.fy = fy;
    params.pixel_step = stride;
    PartModeEstimation estimation;
    estimation.setParams (params);
    found = estimation.compute (labels, *body, parts);
  }
  if (ms)
    *ms = {std::chrono::duration<double, std::milli> (labelled - start).count (),
           std::chrono::duration<double, std::milli> (std::chrono::steady_clock::now () - labelled).count ()};
  return found;
}
}  // namespace agex
