#include "solvers/material/checkpoint_files.h"

#include <fcntl.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "solvers/common/byte_stream.h"
#include "solvers/common/errors.h"

namespace gonogo::material::checkpoint {

namespace {
constexpr char kPointsTag[9] = "GNGPTS01";
constexpr char kManifestTag[9] = "GNGPTM02";
}  // namespace

std::string PointsFile(const std::string& directory, std::uint64_t generation, int rank) {
  return directory + "/points." + std::to_string(generation) + "." + std::to_string(rank) + ".bin";
}

std::string ManifestFile(const std::string& directory, std::uint64_t generation) {
  return directory + "/points." + std::to_string(generation) + ".manifest";
}

void WriteFileAtomically(const std::string& path, const std::string& bytes, unsigned permissions) {
  const std::string temporary = path + ".tmp";
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC,
                        static_cast<mode_t>(permissions));
  if (fd < 0) throw std::runtime_error("cannot create " + temporary);
  std::size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
    if (n <= 0) {
      ::close(fd);
      std::remove(temporary.c_str());
      throw std::runtime_error("cannot write " + temporary + " (disk full?)");
    }
    written += static_cast<std::size_t>(n);
  }
  const bool synced = ::fsync(fd) == 0;
  ::close(fd);
  if (!synced || std::rename(temporary.c_str(), path.c_str()) != 0) {
    throw std::runtime_error("cannot commit " + path);
  }
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("checkpoint", "cannot open " + path);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

std::string PointsFileBytes(const std::string& model_name,
                            const std::vector<std::pair<Handle, std::string>>& points) {
  ByteWriter out;
  out.PutTag(kPointsTag);
  out.PutBlob(model_name);
  out.Put(static_cast<std::uint64_t>(points.size()));
  for (const auto& [handle, bytes] : points) {
    out.Put(static_cast<std::int64_t>(handle));
    out.PutBlob(bytes);
  }
  return out.Take();
}

std::string ManifestBytes(const Manifest& manifest) {
  ByteWriter out;
  out.PutTag(kManifestTag);
  out.Put(manifest.generation);
  out.PutBlob(manifest.model_name);
  out.Put(manifest.files);
  out.Put(manifest.points);
  return out.Take();
}

Manifest ReadManifest(const std::string& directory, std::uint64_t generation) {
  const std::string path = ManifestFile(directory, generation);
  const std::string bytes = ReadFile(path);
  Manifest manifest;
  try {
    ByteReader in(bytes);
    in.ExpectTag(kManifestTag);
    in.Get(manifest.generation);
    in.GetBlob(manifest.model_name);
    in.Get(manifest.files);
    in.Get(manifest.points);
  } catch (const InputError& e) {
    throw InputError("checkpoint", path + ": " + e.what());
  }
  Require(manifest.generation == generation, "checkpoint", path + " is of another generation");
  return manifest;
}

std::unordered_map<Handle, std::string> LoadPointBytes(const std::string& directory,
                                                       const Manifest& manifest,
                                                       const std::vector<Handle>& wanted) {
  std::unordered_map<Handle, std::string> loaded;
  std::unordered_map<Handle, bool> want;
  for (Handle handle : wanted) want[handle] = true;
  for (std::uint32_t file = 0; file < manifest.files; ++file) {
    const std::string path = PointsFile(directory, manifest.generation, static_cast<int>(file));
    const std::string bytes = ReadFile(path);
    try {
      ByteReader in(bytes);
      in.ExpectTag(kPointsTag);
      std::string model_name;
      in.GetBlob(model_name);
      Require(model_name == manifest.model_name, "checkpoint",
              "holds points of '" + model_name + "', not '" + manifest.model_name + "'");
      std::uint64_t count = 0;
      in.Get(count);
      for (std::uint64_t k = 0; k < count; ++k) {
        std::int64_t handle = 0;
        std::string state;
        in.Get(handle);
        in.GetBlob(state);
        if (want.count(handle) != 0) loaded[handle] = std::move(state);
      }
    } catch (const InputError& e) {
      throw InputError("checkpoint", path + ": " + e.what());
    }
  }
  for (Handle handle : wanted) {
    Require(loaded.count(handle) != 0, "checkpoint",
            "point " + std::to_string(handle) + " is in no points file of generation " +
                std::to_string(manifest.generation));
  }
  return loaded;
}

void RemoveGeneration(const std::string& directory, std::uint64_t generation) {
  std::error_code ignored;
  const std::string prefix = "points." + std::to_string(generation) + ".";
  for (const auto& entry : std::filesystem::directory_iterator(directory, ignored)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(prefix, 0) == 0) std::filesystem::remove(entry.path(), ignored);
  }
}

}  // namespace gonogo::material::checkpoint
