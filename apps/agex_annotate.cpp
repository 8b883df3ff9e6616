// agex_annotate: 180-landmark body-contour annotations without a human.
//   agex_annotate coco --json FILE --images DIR --out XML    COCO polygons or RLE masks (+ keypoints)
//   agex_annotate masks --images DIR --masks DIR --out XML   label maps or instance masks (PNG)
//   agex_annotate rgbd INPUT... --out XML                      organized XYZRGBA clouds
// Writes a dlib/imglab XML dataset (square boxes, parts 000-179, shoulders when known)
// for agex_landmarks_train, agex_landmarks_eval and imglab.

#include <agex/apps/annotate_runs.h>

#include <iostream>
#include <string>

int
main (int argc, char **argv)
{
  const std::string usage = "usage: agex_annotate coco --json FILE --images DIR --out XML [options]\n"
                            "       agex_annotate masks --images DIR --masks DIR --out XML [options]\n"
                            "       agex_annotate rgbd INPUT... --out XML [options]\n"
                            "(agex_annotate SUBCOMMAND --help for the options)";
  const std::string sub = argc >= 2 ? argv[1] : "";
  if (sub != "coco" && sub != "masks" && sub != "rgbd")
  {
    const bool help = sub == "--help" || sub == "-h";
    (help ? std::cout : std::cerr) << usage << "\n";
    return help ? 0 : 1;
  }
  try
  {
    if (sub == "coco")
      return agex::apps::annotateCoco (argc - 1, argv + 1);
    return sub == "masks" ? agex::apps::annotateMasks (argc - 1, argv + 1) : agex::apps::annotateRgbd (argc - 1, argv + 1);
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_annotate: error: " << e.what () << "\n";
    return 1;
  }
}
