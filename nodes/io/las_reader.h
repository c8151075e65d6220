#pragma once
// LAS (ASPRS LiDAR exchange format) reader, versions 1.0-1.4, uncompressed point data formats
// 0-3 and 6-8. No Debian library reads LAS; the format is small and documented (ASPRS LAS 1.4
// R15, "Public Header Block" and "Point Data Records").

#include <functional>
#include <string>

#include "runtime/point_cloud.h"

namespace meshflow::io {

/// Reads the points of a LAS file: x y z (the records' integers times the header's scale plus
/// its offset, metres as stored), intensity, and RGB for formats 2, 3, 7 and 8 (16-bit
/// channels; scaled to 8 bits unless every value is already below 256). The point count is the
/// 64-bit one of LAS 1.4 headers, else the legacy 32-bit one; records may be longer than their
/// format's minimum (extra bytes are skipped). Throws meshflow::Error naming the file and
/// field for: a missing "LASF" signature, LAZ (compressed) point data ("decompress it first"),
/// another point format, a record length below the format's, a header or point count the file
/// cannot hold (checked before any allocation), and a point more than 1e6 m from the first.
/// Georeferenced files (the first point beyond 10 km of the world origin, e.g. UTM) are read
/// in a local frame: PointCloud::origin is the first point rounded to whole kilometres and the
/// positions are relative to it, exact to the file's resolution (floats near the world origin
/// instead of millions of metres). O(file size), streamed in chunks.
PointCloud read_las(const std::string& path);

/// read_las() in pieces: the points in file order, `batch` (>= 1) at a time, each piece in the
/// local frame of the first point (the same origin for all), so a file larger than memory can be
/// streamed (the out-of-core path). Colours are scaled as read_las() scales them (a first pass
/// over the colour fields decides). The cloud passed to `sink` is reused after it returns.
/// Throws as read_las() does, possibly after some pieces.
void read_las_batches(const std::string& path, std::size_t batch,
                      const std::function<void(const PointCloud&)>& sink);

}  // namespace meshflow::io
