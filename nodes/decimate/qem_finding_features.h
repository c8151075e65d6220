#pragma once
// QEM decimation (qem_decimation.h) whose feature edges are found while the part of its setup
// that needs none of them runs: for callers that detect the features just before decimating
// (the optimize step). A header of its own, so that the many users of qem_decimation.h do not
// depend on <functional>.

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "nodes/decimate/qem_decimation.h"
#include "runtime/vertex_triangles.h"

namespace meshflow {

/// Sharp edges the decimation keeps: {a, b} vertex pairs of the input, any order.
using QemFeatureEdges = std::vector<std::array<std::uint32_t, 2>>;

/// qem_decimate(mesh, feature_edges, config, report) with the feature edges that
/// `find_features` returns (called once, on any thread, with vertex_triangles(mesh), which the
/// decimator builds for its neighbour rings and shares so that the detection need not build it
/// again; what it returns must stay valid until this returns), found beside the setup that
/// needs none of them (neighbour rings, face quadrics): with two threads the detection costs
/// little besides. The same output as passing its result; exceptions from either side
/// propagate.
TriangleMesh qem_decimate_finding_features(
    const TriangleMesh& mesh,
    const std::function<const QemFeatureEdges&(const VertexTriangles&)>& find_features,
    const QemConfig& config, QemReport* report = nullptr);

}  // namespace meshflow
