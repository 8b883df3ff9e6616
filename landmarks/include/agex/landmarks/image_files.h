#pragma once
// Photos and masks from outside, read defensively. OpenCV alone would open a FIFO and wait
// forever, allocate whatever size a header claims, decode a truncated JPEG with a warning and
// grey rows, and give a palette PNG's colours instead of its indices (so that the person
// numbers of Penn-Fudan's instance masks would be lost).

#include <opencv2/core.hpp>

#include <string>

namespace agex
{
/** \brief Reads an image (cv::imread flags). Refuses, naming the file and what it was needed
  * for (role, e.g. "an image of dataset.xml"): files that are not regular files, unreadable or
  * undecodable files, files over agex::kMaxImageFileBytes, images over agex::kMaxFramePixels
  * (checked in the header before any decoding: agex/io/image_header.h, which also refuses
  * formats it does not check), and truncated JPEGs.
  * \throws std::runtime_error */
cv::Mat readImage (const std::string &path, int flags, const std::string &role = "");

/** \brief A label or instance mask: 8 or 16-bit grey as stored, or a palette PNG as its
  * indices (CV_8UC1; a colour listed twice in the palette means its first index).
  * \throws std::runtime_error naming the file: unreadable, a colour image that is not a
  * palette PNG, or a pixel whose colour is not in the palette */
cv::Mat readLabelImage (const std::string &path);
}  // namespace agex
