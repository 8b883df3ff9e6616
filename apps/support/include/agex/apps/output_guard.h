#pragma once
// "May I write here?": one answer for every app that writes over a path it is given. An output
// may replace only an earlier output of the same kind, recognised by its content (never by
// its name), and never an input, a directory holding one, or anything inside an input dataset.

#include <agex/io/atomic_file.h>

#include <functional>
#include <string>
#include <vector>

namespace agex
{
namespace apps
{
/** What an output is, as its content shows. */
enum class OutputKind
{
  Dataset,       ///< an agex dataset directory (agex_convert, agex_synth)
  JsonDocument,  ///< a pretty-printed JSON object with a "frame" (one frame's result)
  JsonLines,     ///< one JSON line per frame (runs over several frames; ResultsFile checks the lines)
  Png,           ///< a PNG that agex wrote (writePng marks it; see isAgexPng)
  Forest,        ///< an agex body-part forest file (starts with its AGEXFRST magic)
  Json,          ///< any JSON document agex wrote (a report): a file that parses as a JSON object
  Model,         ///< an agex detector model (YAML with "format: agex-model" in its header)
  ImglabXml,     ///< an imglab dataset that agex_annotate wrote (its comment names agex_annotate)
};

/** How an app tells its own earlier output when the content needs more than OutputKind
  * knows (a report's keys, a model only its loader understands): given an existing,
  * non-empty regular file, why it is not an earlier output of this kind ("exists and is
  * not ..."), or "" if it is. */
using OutputRecogniser = std::function<std::string (const std::string &path)>;

/** A JSON object holding every one of keys (a report of one app). */
OutputRecogniser jsonReportWith (const std::vector<std::string> &keys);

/** JSON lines, each an object holding every one of keys (one line per frame or image). */
OutputRecogniser jsonLinesWith (const std::vector<std::string> &keys);

/** \brief Refuses an output path unless writing there loses nothing: the path must not be an
  * input, a directory holding one or a path inside an input dataset (inputs.checkOutput), and
  * if something is there already it must be an earlier output of the same kind: for Dataset
  * an agex dataset holding only its own files (agex::datasetReplaceProblem), replaced only
  * with force; for JsonDocument a JSON object with a "frame", not a JSON-lines file; for
  * JsonLines a regular file; for Png a PNG agex wrote; for Forest a forest file; for
  * Json a JSON object. An empty regular file holds nothing and
  * may be replaced by any kind of file.
  * \throws std::runtime_error naming the path and why */
void checkOutputPath (const std::string &path, OutputKind kind, const InputFiles &inputs, bool force = false);

/** \brief The same rule for an output recognised by recognise: not an input, and if a
  * non-empty file is there, one that recognise takes for an earlier output (what names the
  * kind in the refusal). \throws std::runtime_error naming the path and why */
void checkOutputPath (const std::string &path, const std::string &what, const OutputRecogniser &recognise,
                      const InputFiles &inputs);

/** \brief Each PNG a run writes into a folder (one per image): the folder must not be an
  * input, and each file there must be an earlier agex PNG, checked before the run writes any.
  * \throws std::runtime_error naming the first path that would lose something */
void checkPngsInFolder (const std::vector<std::string> &pngs, const InputFiles &inputs);

/** \brief Claims the outputs of one run that belong together (a frame's JSON and its
  * overlays): an exclusive flock(2) on the folder of each, taken in one fixed order and held
  * until destruction. Two runs writing the same set then write one after the other, so the
  * set on disk is always one run's whole set, never a mix. Waits while another run holds
  * the claim (writing a set takes milliseconds). Folders that cannot be opened or locked
  * (the latter with a warning) are skipped: their outputs are still written atomically, one
  * by one. */
class OutputSetClaim
{
public:
  explicit OutputSetClaim (const std::vector<std::string> &paths);
  ~OutputSetClaim ();
  OutputSetClaim (const OutputSetClaim &) = delete;
  OutputSetClaim &operator= (const OutputSetClaim &) = delete;

private:
  std::vector<int> fds_;
};

/** PNG bytes with agex's mark added (a tEXt chunk "Software: agex" after the header), so
  * that a later run can tell its own overlay from any other PNG. Other bytes are returned as
  * they are. */
std::string markAgexPng (const std::string &png);

/** Whether the bytes are a PNG that carries agex's mark (markAgexPng). */
bool isAgexPng (const std::string &bytes);
}  // namespace apps
}  // namespace agex
