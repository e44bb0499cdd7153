#include "solvers/material/point_store.h"

#include <stdexcept>

#include "solvers/common/errors.h"
#include "solvers/material/checkpoint_files.h"
#include <utility>

namespace gonogo::material {

std::size_t LocalPointStore::Index(PointHandle handle) const {
  if (handle < 0 || handle >= size()) {
    throw std::out_of_range(model_.Name() + " point store: no point with handle " +
                            std::to_string(handle));
  }
  return static_cast<std::size_t>(handle);
}

std::vector<PointHandle> LocalPointStore::Create(std::int64_t count) {
  if (count < 0) throw std::invalid_argument("point store: a negative count of points");
  std::vector<PointHandle> handles;
  handles.reserve(static_cast<std::size_t>(count));
  for (std::int64_t k = 0; k < count; ++k) {
    handles.push_back(size());
    committed_.push_back(model_.InitialState());
    trial_.emplace_back();
  }
  return handles;
}

std::vector<TrialResponse> LocalPointStore::TryUpdate(
    const std::vector<PointHandle>& handles,
    const std::vector<Matrix3>& displacement_gradient_increments, bool want_tangent) {
  if (handles.size() != displacement_gradient_increments.size()) {
    throw std::invalid_argument("point store: " + std::to_string(handles.size()) +
                                " handles but " +
                                std::to_string(displacement_gradient_increments.size()) +
                                " increments");
  }
  // Every trial starts from the committed state, whatever trial is pending.
  scratch_.resize(handles.size());
  for (std::size_t k = 0; k < handles.size(); ++k) {
    scratch_[k].displacement_gradient_increment = displacement_gradient_increments[k];
    scratch_[k].committed = committed_[Index(handles[k])].get();
  }
  std::vector<PointResponse> responses = model_.Update(scratch_, want_tangent);
  std::vector<TrialResponse> trials(handles.size());
  for (std::size_t k = 0; k < handles.size(); ++k) {
    PointResponse& response = responses[k];
    TrialResponse& trial = trials[k];
    trial.status = response.status;
    trial.reason = std::move(response.reason);
    trial.stress_pa = response.stress_pa;
    trial.has_tangent = response.has_tangent;
    if (response.has_tangent) trial.tangent_pa = response.tangent_pa;
    // A model that reports success without a state broke the seam: count it as a failure.
    if (trial.status == UpdateStatus::kOk && response.state == nullptr) {
      trial.status = UpdateStatus::kFailed;
      trial.reason = model_.Name() + " returned kOk without a state";
    }
    trial_[handles[k]] = trial.status == UpdateStatus::kOk ? std::move(response.state) : nullptr;
  }
  return trials;
}

void LocalPointStore::Commit(const std::vector<PointHandle>& handles) {
  // Check every handle first, so a refused commit changes nothing.
  for (PointHandle handle : handles) {
    if (trial_[Index(handle)] == nullptr) {
      throw std::logic_error(model_.Name() + " point store: commit of point " +
                             std::to_string(handle) + ", which has no successful trial");
    }
  }
  for (PointHandle handle : handles) {
    if (trial_[handle] != nullptr) committed_[handle] = std::move(trial_[handle]);  // once each
  }
}

void LocalPointStore::Discard(const std::vector<PointHandle>& handles) {
  for (PointHandle handle : handles) trial_[Index(handle)].reset();
}

std::string LocalPointStore::Serialize(PointHandle handle) const {
  return committed_[Index(handle)]->Serialize();
}

void LocalPointStore::Restore(PointHandle handle, const std::string& bytes) {
  const std::size_t index = Index(handle);
  committed_[index] = model_.RestoreState(bytes);  // throws before anything changes
  trial_[index].reset();
}

const MaterialState& LocalPointStore::committed(PointHandle handle) const {
  return *committed_[Index(handle)];
}

void MaterialPointStore::WriteCheckpoint(const std::string& directory,
                                         std::uint64_t generation) {
  std::vector<std::pair<checkpoint::Handle, std::string>> points;
  for (PointHandle handle = 0; handle < size(); ++handle) {
    points.emplace_back(handle, Serialize(handle));
  }
  checkpoint::WriteFileAtomically(checkpoint::PointsFile(directory, generation, 0),
                                  checkpoint::PointsFileBytes(ModelName(), points));
  checkpoint::Manifest manifest;
  manifest.generation = generation;
  manifest.model_name = ModelName();
  manifest.files = 1;
  manifest.points = static_cast<std::uint64_t>(size());
  checkpoint::WriteFileAtomically(checkpoint::ManifestFile(directory, generation),
                                  checkpoint::ManifestBytes(manifest));
  if (generation >= 2) checkpoint::RemoveGeneration(directory, generation - 2);
}

void MaterialPointStore::ReadCheckpoint(const std::string& directory, std::uint64_t generation) {
  const checkpoint::Manifest manifest = checkpoint::ReadManifest(directory, generation);
  Require(manifest.model_name == ModelName(), "checkpoint",
          "holds points of '" + manifest.model_name + "', not '" + ModelName() + "'");
  Require(manifest.points == static_cast<std::uint64_t>(size()), "checkpoint",
          "holds " + std::to_string(manifest.points) + " points; this store has " +
              std::to_string(size()));
  std::vector<checkpoint::Handle> wanted;
  for (PointHandle handle = 0; handle < size(); ++handle) wanted.push_back(handle);
  const auto loaded = checkpoint::LoadPointBytes(directory, manifest, wanted);
  // All or nothing: the states as they were come back if one cannot be read.
  std::vector<std::string> before;
  for (PointHandle handle = 0; handle < size(); ++handle) before.push_back(Serialize(handle));
  try {
    for (PointHandle handle = 0; handle < size(); ++handle) Restore(handle, loaded.at(handle));
  } catch (const std::exception& e) {
    for (PointHandle handle = 0; handle < size(); ++handle) Restore(handle, before[handle]);
    throw InputError("checkpoint", std::string("a point state cannot be read: ") + e.what());
  }
}

}  // namespace gonogo::material
