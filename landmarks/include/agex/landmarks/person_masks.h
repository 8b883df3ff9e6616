#pragma once
// Person masks from the common annotation formats: COCO run-length encoding (RLE, both the
// compressed string and the plain list of counts), label maps (a clothing / body-part label
// per pixel, as in the Clothing Co-Parsing dataset) and instance masks (value k = person k, as
// in Penn-Fudan's PedMasks). Masks are CV_8UC1, 255 = person.

#include <opencv2/core.hpp>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace agex
{
/** \brief Run lengths from COCO's compressed RLE string (pycocotools' rleFrString): each
  * count is written in 5-bit groups, least significant first, one character per group
  * (ASCII 48 + the group, bit 0x20 set when more groups follow, bit 0x10 of the last group the
  * sign), and from the fourth count on as the difference to the count two before.
  * \throws std::invalid_argument on a character outside '0'..'o', a count cut off at the end
  * of the string, a count that does not fit 32 bits or a negative count */
std::vector<std::uint32_t> cocoRleCountsFromString (const std::string &counts);

/** The compressed string of run lengths (pycocotools' rleToString). */
std::string cocoRleString (const std::vector<std::uint32_t> &counts);

/** \brief A mask from COCO run lengths: alternating runs of background and person pixels,
  * background first, in column-major order (down the first column, then the next).
  * \throws std::invalid_argument when the counts do not add up to height x width or the size
  * is not positive */
cv::Mat maskFromCocoRle (const std::vector<std::uint32_t> &counts, int height, int width);

/** The COCO run lengths of a mask (non-zero = set), column-major, background first. */
std::vector<std::uint32_t> cocoRleFromMask (const cv::Mat &mask);

/** The person of a label map, and what it took to get it. */
struct LabelMapPerson
{
  cv::Mat mask;             ///< CV_8UC1, 255 = person; empty when problem is set
  std::string problem;      ///< why there is no person (empty mask, only excluded labels)
  int bridged_pixels = 0;   ///< excluded pixels put back to keep the body in one piece
  bool whole_excluded_region_kept = false;  ///< no narrow bridge joined the body: all of it kept
};

/** \brief The person of a label map (CV_8UC1 or CV_16UC1; 0 = background): every pixel whose
  * label is neither 0 nor in excluded. Excluded labels (a bag, a purse) bulge the outline,
  * but leaving them out can split the body (a bag held in front of the legs): then the
  * pieces that the excluded region joined are joined again through the excluded pixels
  * between them, the narrowest bridge that does it (a closing of the body restricted to the
  * excluded pixels, of growing radius up to a quarter of the body's height; failing that, the
  * whole excluded region is kept). Pieces the excluded region did not join are left as they
  * are. \throws std::invalid_argument on another image type */
LabelMapPerson personFromLabelMap (const cv::Mat &labels, const std::vector<int> &excluded);

/** \brief The people of an instance mask (CV_8UC1 or CV_16UC1): value k > 0 is person k.
  * Returns (k, mask) by increasing k. \throws std::invalid_argument on another image type */
std::vector<std::pair<int, cv::Mat>> peopleFromInstanceMask (const cv::Mat &instances);
}  // namespace agex
