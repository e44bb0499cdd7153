// The recipe's loss weights for its random walks (WalkShareWeights, SurrogateRecipe::walk_share).
#include "solvers/tiers/surrogate_training.h"

#include <gtest/gtest.h>

#include <cstddef>

#include "solvers/common/errors.h"

namespace gonogo::tiers {
namespace {

ann::StrainHistory HistoryOfSteps(std::size_t steps) {
  ann::StrainHistory history;
  history.increments.assign(steps, ann::Matrix3::Zero());
  history.stresses_pa.assign(steps, ann::Vector6::Zero());
  return history;
}

// The recipe's training paths' histories (walks among them, one stopped early), then two rig
// paths: the walks' steps carry the asked share of the loss, every other step weighs 1.
TEST(WalkShareWeights, GiveTheWalksTheirShareOfTheLoss) {
  SurrogateRecipe recipe;
  recipe.steps = 10;
  recipe.walks = 3;
  const std::vector<NamedLabPath> paths = TrainingPaths(recipe);
  std::vector<ann::StrainHistory> histories;
  double walk_steps = 0, other_steps = 0;
  int walks = 0;
  for (std::size_t k = 0; k < paths.size(); ++k) {
    const std::size_t steps = k == 0 ? 4 : 10;  // the first path stopped after 4 steps
    histories.push_back(HistoryOfSteps(steps));
    const bool walk = paths[k].spec.path == ann::LabPath::kRandomWalk;
    walks += walk;
    (walk ? walk_steps : other_steps) += static_cast<double>(steps);
  }
  ASSERT_EQ(walks, 3);
  for (const std::size_t rig_steps : {200u, 300u}) {
    histories.push_back(HistoryOfSteps(rig_steps));
    other_steps += static_cast<double>(rig_steps);
  }

  const std::vector<double> weights = WalkShareWeights(paths, histories, 0.6);
  ASSERT_EQ(weights.size(), histories.size());
  double walk_loss = 0, all_loss = 0;
  for (std::size_t k = 0; k < histories.size(); ++k) {
    const bool walk = k < paths.size() && paths[k].spec.path == ann::LabPath::kRandomWalk;
    if (!walk) {
      EXPECT_EQ(weights[k], 1.0) << k;
    }
    walk_loss += walk ? weights[k] * static_cast<double>(histories[k].steps()) : 0.0;
    all_loss += weights[k] * static_cast<double>(histories[k].steps());
  }
  EXPECT_NEAR(walk_loss / all_loss, 0.6, 1e-12);
  EXPECT_GT(weights.back(), 0);
  EXPECT_NEAR(walk_loss, 0.6 / 0.4 * other_steps, 1e-9 * other_steps) << walk_steps;

  // No walks: nothing to weigh.
  recipe.walks = 0;
  const std::vector<NamedLabPath> no_walks = TrainingPaths(recipe);
  const std::vector<double> ones = WalkShareWeights(
      no_walks, std::vector<ann::StrainHistory>(no_walks.size(), HistoryOfSteps(5)), 0.6);
  for (double weight : ones) EXPECT_EQ(weight, 1.0);
}

TEST(WalkShareWeights, TheRecipeRefusesAShareItCannotGive) {
  auto refused = [](const SurrogateRecipe& recipe) {
    try {
      recipe.Validate("recipe.");
      return std::string("accepted");
    } catch (const InputError& e) {
      return e.field();
    }
  };
  SurrogateRecipe recipe;
  recipe.walk_share = 0.6;
  EXPECT_EQ(refused(recipe), "accepted");
  for (const double share : {-0.1, 0.995, 1.0}) {
    recipe.walk_share = share;
    EXPECT_EQ(refused(recipe), "recipe.walk_share") << share;
  }
  recipe.walk_share = 0.6;
  recipe.rotated_copies = 2;
  EXPECT_EQ(refused(recipe), "recipe.walk_share");
  recipe.rotated_copies = 0;
  recipe.training.history_weights = {1.0};
  EXPECT_EQ(refused(recipe), "recipe.walk_share");
}

}  // namespace
}  // namespace gonogo::tiers
