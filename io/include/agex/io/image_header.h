#pragma once
// Image files checked before OpenCV decodes them. OpenCV picks its decoder by the file's
// content and allocates whatever size the header claims (a 27 KB 1-bit TIFF claims 32767 x
// 32767, 3 GB): the format is identified here by the same magic bytes, and its size read from
// its header, for every format agex lets OpenCV decode; other formats are refused.

#include <opencv2/core/mat.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace agex
{
/** Largest image file read into memory (256 MiB: an uncompressed 16.7 M pixel RGBA image of
  * 16-bit samples has 134 MB), checked on the file's size before reading. */
constexpr std::uint64_t kMaxImageFileBytes = std::uint64_t (1) << 28;

/** What an image's header says. */
struct ImageHeader
{
  std::string format;                   ///< "PNG", "JPEG", "TIFF", "WebP", "BMP", "PNM", "PAM", "PFM", "Sun raster"
  std::uint64_t width = 0, height = 0;  ///< as the decoder will take it
};

/** \brief Identifies an image by its first bytes and reads the size its header claims, as
  * OpenCV's decoder for that format will: PNG (IHDR), JPEG (the first frame header; every
  * frame header must agree, and the data must reach its end-of-image marker), classic TIFF
  * (the first directory), WebP (VP8X canvas, else VP8 or VP8L), BMP, PNM (P1-P6), PAM, PFM,
  * Sun raster.
  * \return "" if the header was read, else what is wrong (an unknown or unchecked format, a
  *         damaged or truncated header) */
std::string parseImageHeader (const unsigned char *data, std::size_t size, ImageHeader &header);

/** \brief Reads an image file for decoding: a regular file of at most kMaxImageFileBytes
  * (stat first), in a format parseImageHeader reads, of at most kMaxFramePixels.
  * \throws FrameError "path: problem" */
std::vector<unsigned char> readImageBytes (const std::string &path, ImageHeader &header);

/** \brief cv::imdecode of bytes that readImageBytes read; OpenCV's own refusals (it throws
  * cv::Exception, e.g. past its pixel limit when it reads a header otherwise) become errors
  * naming the file. \return an empty image where OpenCV cannot decode the bytes
  * \throws FrameError "path: problem" */
cv::Mat decodeImageBytes (const std::string &path, const std::vector<unsigned char> &bytes, int flags);

/** \brief readImageBytes, then cv::imdecode with flags; the bytes are handed out if asked for.
  * \throws FrameError "path: problem", also when OpenCV cannot decode it */
cv::Mat readImageFile (const std::string &path, int flags, std::vector<unsigned char> *bytes = nullptr);
}  // namespace agex
