#pragma once
// The colour coder of a compressed mesh body (nodes/compress/mesh_codec.h), run after the
// connectivity and the positions (a decoder holds the whole decoded geometry then):
//  - prediction: the mean of the vertex's one-ring neighbours decoded before it, weighted by
//    the inverse fourth power of their grid distance (the nearest dominates: extracted vertices
//    take their colours from the nearest cloud points, so a close neighbour's colour is close);
//    the previous vertex's colour without any. Integer arithmetic only.
//  - decorrelation: the three channel residuals in one of six orders, the second predicted
//    from the first and the third from both with coefficients in 1/64 (reversible on integers);
//    the encoder fits them by least squares and picks the order whose residuals cost least
//    (a sensor whose red and green move together, or a grey scene, costs one channel and two
//    near-zero ones); order and coefficients are written first.
//  - contexts: per channel, the expected residual size from the neighbours' spread around the
//    prediction, the residuals they were coded with, and what vertices as far from their
//    nearest decoded neighbour have needed so far (learnt as the stream goes); the first
//    channel also by that distance's class, the later ones by the sizes of the residuals
//    coded before them.
// Exact at 8 bits. Not thread-safe per call; O(V + T) (a row sort per vertex of the adjacency).

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "nodes/compress/attribute_coder.h"
#include "nodes/compress/range_coder.h"
#include "nodes/compress/vertex_adjacency.h"
#include "runtime/rgb8.h"

namespace meshflow::compress {

/// Codes `colors` (one per grid vertex, output order), exactly. Serial; O(V + T).
void encode_colors(const DecodedGeometry& g, const std::vector<Rgb8>& colors, RangeEncoder& enc);

/// What the colour prediction needs of the geometry alone (no colour): the adjacency and, per
/// vertex, the weights of its neighbours decoded before it. A decoder builds it beside the
/// normals (nodes/compress/mesh_codec.cpp: on a second thread).
struct ColorNeighbourhood {
  VertexAdjacency adj;
  std::vector<std::uint32_t> decoded_end;   ///< per vertex: end of its row's decoded prefix
  std::vector<std::uint8_t> distance_bits;  ///< per vertex: bit length of nearest distance^2 + 1
  std::vector<std::uint32_t> weight;        ///< per prefix entry: its weight (<= 2^16)
};

/// The neighbourhood of the vertices of `grid` (output order) from their adjacency `adjacency`
/// (vertex_adjacency() of the output triangles). Thread-safe (reads only its inputs);
/// O(V + T).
ColorNeighbourhood color_neighbourhood(VertexAdjacency adjacency,
                                       const std::vector<std::array<std::int32_t, 3>>& grid);

/// Reads what encode_colors() wrote for the geometry `nb` was built from; a corrupt stream gives
/// some colours (RangeDecoder::check() or the file's checksum reports it). Serial; O(V + T).
std::vector<Rgb8> decode_colors(const ColorNeighbourhood& nb, RangeDecoder& dec,
                                const std::string& source);

}  // namespace meshflow::compress
