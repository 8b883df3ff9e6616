#pragma once
// agex_annotate's subcommands, one function each: its flags parsed from argc/argv (argv[0]
// is the subcommand), the library's annotation sources (agex/landmarks/annotation_sources.h,
// agex::RgbdContourAnnotator) run over the inputs, the imglab dataset, overlays and a summary
// line written. Each returns the exit code and throws std::exception on bad input.

namespace agex
{
namespace apps
{
/** agex_annotate coco: COCO person masks (polygons or RLE) and keypoints. */
int annotateCoco (int argc, char **argv);
/** agex_annotate masks: a folder of images and one of label maps or instance masks. */
int annotateMasks (int argc, char **argv);
/** agex_annotate rgbd: organized XYZRGBA clouds, people from the depth stages. */
int annotateRgbd (int argc, char **argv);
}  // namespace apps
}  // namespace agex
