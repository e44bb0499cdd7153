// The files of a material-point checkpoint, shared by every point store (point_store.h): one
// points file per rank, `points.<generation>.<rank>.bin` (the committed states of the points that
// rank holds, as MaterialState bytes by handle), and `points.<generation>.manifest` (model, rank
// files, point count), each written to a temporary file, fsync-ed and renamed, so a crash leaves
// whole files or none. The manifest is written last: a generation without one is incomplete. A
// checkpoint written by a group of any size reads back into a store of another (every reader
// takes the handles it holds from every points file).
#pragma once

#include <cstdint>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace gonogo::material::checkpoint {

using Handle = std::int64_t;

std::string PointsFile(const std::string& directory, std::uint64_t generation, int rank);
std::string ManifestFile(const std::string& directory, std::uint64_t generation);

// Writes `bytes` to a temporary file beside `path`, fsync-s it and renames it to `path`, so that a
// crash leaves the whole file or the one before. The file is created with `permissions` less the
// process's umask: 0600, the owner's alone, for a checkpoint; 0666 for a file a user reads as any
// other (a curve's CSV). Throws std::runtime_error naming the file when it cannot be written in
// full (disk full).
void WriteFileAtomically(const std::string& path, const std::string& bytes,
                         unsigned permissions = 0600);
// Throws InputError("checkpoint", ...) when the file cannot be read.
std::string ReadFile(const std::string& path);

std::string PointsFileBytes(const std::string& model_name,
                            const std::vector<std::pair<Handle, std::string>>& points);

struct Manifest {
  std::uint64_t generation = 0;
  std::string model_name;
  std::uint32_t files = 0;   // points files, ranks 0..files-1
  std::uint64_t points = 0;  // handles 0..points-1
};
std::string ManifestBytes(const Manifest& manifest);
// Throws InputError("checkpoint", ...) for a missing or damaged manifest.
Manifest ReadManifest(const std::string& directory, std::uint64_t generation);

// The state bytes of `wanted` from every points file of the generation. Throws
// InputError("checkpoint", ...) for a damaged or foreign file or a point that is in none.
std::unordered_map<Handle, std::string> LoadPointBytes(const std::string& directory,
                                                       const Manifest& manifest,
                                                       const std::vector<Handle>& wanted);

// Removes the files of a generation (what exists of them); never throws.
void RemoveGeneration(const std::string& directory, std::uint64_t generation);

}  // namespace gonogo::material::checkpoint
