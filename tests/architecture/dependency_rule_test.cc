// The one dependency rule (ARCHITECTURE section 3), checked on the source tree: solvers/ includes no
// gRPC, protobuf, SQLite or GDAL; cache/ no gRPC, protobuf or GDAL; only server/geo/ includes GDAL.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

const std::regex kGdal(R"(#\s*include\s*[<"](gdal|ogr|cpl_)[^>"]*[>"])");
const std::regex kGrpc(R"(#\s*include\s*[<"](grpc|grpcpp|google/protobuf|gonogo/v1)[^>"]*[>"])");
const std::regex kSqlite(R"(#\s*include\s*[<"]sqlite3\.h[>"])");

// "path:line: include" for every matching include under `dir`.
std::vector<std::string> Offences(const fs::path& root, const std::string& dir, const std::regex& re,
                                  const std::string& except = "") {
  std::vector<std::string> found;
  for (const auto& entry : fs::recursive_directory_iterator(root / dir)) {
    const std::string ext = entry.path().extension().string();
    if (ext != ".h" && ext != ".cc" && ext != ".cpp" && ext != ".hpp") continue;
    const std::string rel = fs::relative(entry.path(), root).string();
    if (!except.empty() && rel.rfind(except, 0) == 0) continue;
    std::ifstream in(entry.path());
    std::string line;
    for (int n = 1; std::getline(in, line); ++n) {
      if (std::regex_search(line, re)) found.push_back(rel + ":" + std::to_string(n) + ": " + line);
    }
  }
  return found;
}

fs::path Root() { return fs::path(std::getenv("GONOGO_SOURCE_DIR")); }

TEST(DependencyRule, SolversIncludeNoServiceOrStorageLibraries) {
  EXPECT_EQ(Offences(Root(), "solvers", kGdal), std::vector<std::string>{});
  EXPECT_EQ(Offences(Root(), "solvers", kGrpc), std::vector<std::string>{});
  EXPECT_EQ(Offences(Root(), "solvers", kSqlite), std::vector<std::string>{});
}

TEST(DependencyRule, CacheSeesOnlySolverTypesAndSqlite) {
  EXPECT_EQ(Offences(Root(), "cache", kGdal), std::vector<std::string>{});
  EXPECT_EQ(Offences(Root(), "cache", kGrpc), std::vector<std::string>{});
}

TEST(DependencyRule, OnlyServerGeoIncludesGdal) {
  EXPECT_EQ(Offences(Root(), "server", kGdal, "server/geo"), std::vector<std::string>{});
  EXPECT_EQ(Offences(Root(), "clients", kGdal), std::vector<std::string>{});
}

TEST(DependencyRule, TheCheckerSeesAnInclude) {
  // Guards against a checker that can never fail: server/geo does include GDAL.
  EXPECT_FALSE(Offences(Root(), "server/geo", kGdal).empty());
}

}  // namespace
