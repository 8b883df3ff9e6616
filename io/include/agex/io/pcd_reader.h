#pragma once
// agex's own PCD reader. PCL's (pcl::PCDReader) trusts the file: fuzzing found heap damage in
// its header parser, its ascii reader and its LZF decompressor. This one checks every size
// before it allocates or writes anything, so a hostile file ends in an agex::FrameError.

#include <agex/io/frame_io.h>

#include <pcl/PCLPointCloud2.h>

#include <cstddef>
#include <string>

namespace agex
{
/** The largest point readPcd reads, in bytes (a PointXYZRGBA frame has 16, a VFH
  * descriptor 1232). */
constexpr std::size_t kMaxPcdPointBytes = std::size_t (1) << 16;

/** The most point data readPcd reads into one cloud (1 GiB: kMaxFramePixels points of 64
  * bytes). While reading it holds the file's data section besides: ascii text up to this
  * size, or a compressed block and its decompressed copy, each about this size at most. */
constexpr std::size_t kMaxPcdDataBytes = std::size_t (1) << 30;

/** \brief Reads a PCD file (header v0.5-0.7 as PCL writes and reads them; DATA ascii, binary
  * or binary_compressed) into a cloud with packed, point-major data, as pcl::PCDReader would
  * (but is_dense comes from x, y, z only).
  *
  * Stricter than PCL: each header keyword at most once and spelled exactly (VERSION, COUNT
  * and VIEWPOINT may be left out; COUNT defaults to 1); SIZE, COUNT, WIDTH, HEIGHT and POINTS
  * whole numbers; one SIZE and TYPE (and COUNT) per field, each SIZE one its TYPE has (F: 4, 8;
  * I, U: 1, 2, 4, 8; B: 1; the letter in either case); WIDTH x HEIGHT == POINTS and at most
  * kMaxFramePixels; ascii lines with exactly one number per value, each fitting its type
  * ("nan" and "inf" for floats; too small for a float reads as a denormal or zero); binary
  * data at least as long as the points; binary_compressed data that decompresses to exactly
  * the points, every LZF copy inside both buffers.
  * \throws FrameError naming the file and the problem */
pcl::PCLPointCloud2 readPcd (const std::string &path);
}  // namespace agex
