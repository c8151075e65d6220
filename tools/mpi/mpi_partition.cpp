#include "tools/mpi/mpi_partition.h"

#include <algorithm>
#include <exception>
#include <functional>

#include "nodes/io/read_point_cloud.h"
#include "nodes/normals/scene_side.h"
#include "runtime/error.h"
#include "tools/mpi/mpi_bytes.h"

namespace meshflow::cli {
namespace {

// One collective step: every rank runs `work` (its bytes for rank 0, or its error); rank 0
// receives all in rank order into `gathered`; every rank learns the first error (rank order).
std::string gather_step(const std::function<std::vector<unsigned char>()>& work, int rank,
                        int ranks, std::vector<std::vector<unsigned char>>& gathered) {
  std::string error;
  std::vector<unsigned char> mine;
  try {
    mine = work();
  } catch (const std::exception& e) {
    error = "rank " + std::to_string(rank) + ": " + e.what();
  }
  io::ByteWriter w;
  put_string(w, error);
  put_vector(w, mine);
  gathered.clear();
  std::vector<unsigned char> verdict;
  if (rank == 0) {
    std::string first = error;
    gathered.push_back(std::move(mine));
    for (int from = 1; from < ranks; ++from) {
      const std::vector<unsigned char> message = receive_bytes(from);
      const std::string source = "partition step from rank " + std::to_string(from);
      io::ByteReader r(source, message);
      const std::string theirs = get_string(r, "error");
      if (first.empty()) first = theirs;
      gathered.push_back(get_vector<unsigned char>(r, "part"));
    }
    io::ByteWriter v;
    put_string(v, first);
    verdict = std::move(v.out);
  } else {
    send_bytes(w.out, 0);
  }
  broadcast_bytes(verdict);
  io::ByteReader r("partition verdict", verdict);
  return get_string(r, "error");
}

// Reads this rank's range of the input (nothing when it has none).
void read_own_range(const std::string& input, const std::string& columns, const InputParts& parts,
                    std::size_t batch, int rank,
                    const std::function<void(const PointCloud&)>& sink) {
  const auto r = static_cast<std::size_t>(rank);
  if (r >= parts.ranges.size()) return;
  io::for_each_point_batch_in_range(input, columns, parts.ranges[r].first, parts.ranges[r].second,
                                    batch, sink);
}

std::vector<unsigned char> encode_written(const chunk::WrittenPart& part) {
  io::ByteWriter w;
  put_chunk_files(w, part.files);
  put(w, part.has_rows);
  put_rows(w, part.rows);
  put(w, part.bounds);
  w.u64(part.points_read);
  w.u64(part.dropped);
  w.u64(part.rows_written);
  return std::move(w.out);
}

chunk::WrittenPart decode_written(const std::vector<unsigned char>& bytes, int from) {
  const std::string source = "chunk part from rank " + std::to_string(from);
  io::ByteReader r(source, bytes);
  chunk::WrittenPart part;
  part.files = get_chunk_files(r);
  part.has_rows = get<bool>(r, "has rows");
  part.rows = get_rows(r);
  part.bounds = get<Eigen::AlignedBox3f>(r, "bounds");
  part.points_read = r.u64("points read");
  part.dropped = r.u64("dropped");
  part.rows_written = r.u64("rows written");
  return part;
}

// The whole-input decisions from every rank's part of the sample: offers joined on rank 0 and
// sent back, then each rank's measures joined on rank 0. Rank 0's result (others: ignored).
std::string decide_by_ranks(const std::string& input, const std::string& columns,
                            const ReconstructionConfig& config, const ChunkingConfig& chunking,
                            const InputParts& parts, int rank, int ranks, SpacingSample& sample) {
  std::vector<std::vector<unsigned char>> gathered;
  std::string error = gather_step(
      [&] {
        read_own_range(
            input, columns, parts, chunking.batch_points, rank,
            [&](const PointCloud& b) { sample.offer(points_to_sample(b, config.filter)); });
        return sample.to_bytes();
      },
      rank, ranks, gathered);
  if (!error.empty()) return error;
  std::vector<unsigned char> joined;
  if (rank == 0) {
    SpacingSample all = empty_input_sample(config);
    for (std::size_t from = 0; from < gathered.size(); ++from)
      all.merge_offered(
          SpacingSample::from_bytes(gathered[from], "sample from rank " + std::to_string(from)));
    joined = all.to_bytes();
  }
  broadcast_bytes(joined);
  sample = SpacingSample::from_bytes(joined, "joined sample from rank 0");
  error = gather_step(
      [&] {
        read_own_range(
            input, columns, parts, chunking.batch_points, rank,
            [&](const PointCloud& b) { sample.measure(points_to_sample(b, config.filter)); });
        return sample.to_bytes();
      },
      rank, ranks, gathered);
  if (!error.empty() || rank != 0) return error;
  sample = SpacingSample::from_bytes(gathered[0], "sample measured by rank 0");
  for (std::size_t from = 1; from < gathered.size(); ++from)
    sample.merge_measured(SpacingSample::from_bytes(
        gathered[from], "sample measured by rank " + std::to_string(from)));
  return error;
}

}  // namespace

void put_chunk_files(io::ByteWriter& w, const std::vector<chunk::ChunkFile>& files) {
  w.u64(files.size());
  for (const chunk::ChunkFile& f : files) {
    put(w, f.index);
    w.u64(f.core_points);
    w.u64(f.points);
    put_string(w, f.path);
    w.u64(f.parts.size());
    for (const std::string& part : f.parts) put_string(w, part);
  }
}

std::vector<chunk::ChunkFile> get_chunk_files(io::ByteReader& r) {
  const std::uint64_t count = r.u64("chunks");
  if (count > r.remaining()) r.fail("chunks", "more chunks than the message holds");
  std::vector<chunk::ChunkFile> files(count);
  for (chunk::ChunkFile& f : files) {
    f.index = get<Eigen::Vector3i>(r, "chunk index");
    f.core_points = r.u64("core points");
    f.points = r.u64("points");
    f.path = get_string(r, "path");
    const std::uint64_t parts = r.u64("parts");
    if (parts > r.remaining()) r.fail("parts", "more parts than the message holds");
    for (std::uint64_t p = 0; p < parts; ++p) f.parts.push_back(get_string(r, "part path"));
  }
  return files;
}

RankedPartition partition_by_ranks(const std::string& input, const std::string& columns,
                                   const ReconstructionConfig& config,
                                   const ChunkingConfig& chunking, const InputParts& parts,
                                   int rank, int ranks, chunk::PhaseClock& clock) {
  RankedPartition out;
  SpacingSample sample = empty_input_sample(config);
  clock.begin("decide", false);
  const bool sampled = input_needs_sample(config, chunking);
  if (sampled) {
    out.error = decide_by_ranks(input, columns, config, chunking, parts, rank, ranks, sample);
    if (!out.error.empty()) return out;
  }
  // Rank 0: the decisions, the grid from them, the directory.
  std::vector<unsigned char> setup;
  bool z_up = false;
  if (rank == 0)
    clock.begin("setup", true);
  else
    clock.wait("setup");
  if (rank == 0) {
    std::string error;
    try {
      bool normals = false, sensor = false, first = true;
      PointCloud head;
      io::for_each_point_batch_in_range(
          input, columns, 0, std::min<std::uint64_t>(parts.ranges[0].second, chunking.batch_points),
          chunking.batch_points, [&](const PointCloud& b) {
            if (!first) return;
            first = false;
            head = b;
          });
      normals = head.has_normals();
      sensor = head.has_sensor_origin;
      if (sampled) {
        out.decided = decisions_from_sample(sample, config, normals, sensor, input);
      } else {
        out.decided.voxel_size = config.voxelize.voxel_size;
        out.decided.method = config.extract.method;
      }
      out.store = std::make_unique<chunk::ChunkStore>(grid_for_input(out.decided, chunking),
                                                      chunking.directory);
      out.grid = out.store->grid();
      z_up = !head.has_normals() && classify_scene(head) == SceneKind::kHeightField;
    } catch (const std::exception& e) {
      error = e.what();
    }
    io::ByteWriter w;
    put_string(w, error);
    put(w, out.grid);
    put(w, out.decided);
    put_string(w, out.store ? out.store->directory() : std::string());
    setup = std::move(w.out);
  }
  broadcast_bytes(setup);
  io::ByteReader r("partition setup from rank 0", setup);
  out.error = get_string(r, "error");
  out.grid = get<chunk::ChunkGrid>(r, "grid");
  out.decided = get<InputDecisions>(r, "decisions");
  const std::string directory = get_string(r, "directory");
  if (!out.error.empty()) return out;

  // Every rank spills its own range into its own part of the chunk files.
  clock.begin("partition", false);
  std::vector<std::vector<unsigned char>> gathered;
  out.error = gather_step(
      [&] {
        chunk::ChunkWriter writer(out.grid, directory, rank);
        read_own_range(input, columns, parts, chunking.batch_points, rank,
                       [&](const PointCloud& b) { writer.add(b); });
        return encode_written(writer.finish());
      },
      rank, ranks, gathered);
  if (!out.error.empty() || rank != 0) return out;
  clock.begin("join", true);
  try {
    std::vector<chunk::WrittenPart> written;
    for (std::size_t from = 0; from < gathered.size(); ++from)
      written.push_back(decode_written(gathered[from], static_cast<int>(from)));
    out.files = out.store->finish(written);
    if (z_up) out.store->set_z_up();
    if (out.store->points_read() == 0)
      throw Error(input, "points", "no finite points to reconstruct");
    out.rows = out.store->rows();
  } catch (const std::exception& e) {
    out.error = e.what();
  }
  return out;
}

}  // namespace meshflow::cli
