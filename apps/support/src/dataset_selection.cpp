#include <agex/apps/dataset_selection.h>

#include <set>
#include <sstream>
#include <stdexcept>

namespace agex
{
namespace apps
{
DatasetSelection
selectDataset (const std::string &spec, bool keyframes_only)
{
  const auto at = spec.rfind ('@');
  const std::string directory = at == std::string::npos ? spec : spec.substr (0, at);
  std::set<std::string> sequences;
  if (at != std::string::npos)
  {
    std::stringstream in (spec.substr (at + 1));
    for (std::string s; std::getline (in, s, ',');)
      if (!s.empty ())
        sequences.insert (s);
    if (sequences.empty ())
      throw std::runtime_error (spec + ": no sequences after '@'");
  }
  DatasetSelection selection{Dataset::read (directory), {}};
  std::set<std::string> present;
  for (const auto &frame : selection.dataset.frames ())
  {
    present.insert (frame.sequence);
    if (!sequences.empty () && !sequences.count (frame.sequence))
      continue;
    if (keyframes_only && !selection.dataset.isKeyframe (frame.id))
      continue;
    selection.frame_ids.push_back (frame.id);
  }
  for (const auto &s : sequences)
    if (!present.count (s))
      throw std::runtime_error (directory + ": has no sequence '" + s + "'");
  return selection;
}

std::vector<std::string>
datasetFiles (const Dataset &dataset)
{
  std::vector<std::string> files{dataset.directory () + "/dataset.json", dataset.directory () + "/labels.csv"};
  for (const auto &frame : dataset.frames ())
  {
    files.push_back (dataset.framePath (frame.id));
    if (dataset.hasPartLabels ())
      files.push_back (dataset.partLabelPath (frame.id));
    if (dataset.hasPersonLabels ())
      files.push_back (dataset.personLabelPath (frame.id));
  }
  return files;
}
}  // namespace apps
}  // namespace agex
