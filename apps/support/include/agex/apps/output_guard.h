#pragma once
// "May I write here?": one answer for every app that writes over a path it is given. An output
// may replace only an earlier output of the same kind, recognised by its content (never by
// its name), and never an input, a directory holding one, or anything inside an input dataset.

#include <agex/io/atomic_file.h>

#include <string>

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
};

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

/** PNG bytes with agex's mark added (a tEXt chunk "Software: agex" after the header), so
  * that a later run can tell its own overlay from any other PNG. Other bytes are returned as
  * they are. */
std::string markAgexPng (const std::string &png);

/** Whether the bytes are a PNG that carries agex's mark (markAgexPng). */
bool isAgexPng (const std::string &bytes);
}  // namespace apps
}  // namespace agex
