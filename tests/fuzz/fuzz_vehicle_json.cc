// libFuzzer target: the vehicle and soil-table JSON files users write (clients/vehicles/*.json,
// the sample's soil_table.json). The bytes go through the parser the CLI uses (protobuf's JSON
// form, unknown fields refused) and, when they parse, through the server's conversion and
// validation of a vehicle and of a soil table.
#include <google/protobuf/util/json_util.h>

#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_expected.h"
#include "server/request_convert.h"

using namespace gonogo;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string json(reinterpret_cast<const char*>(data), size);
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;
  v1::Vehicle vehicle;
  if (google::protobuf::util::JsonStringToMessage(json, &vehicle, options).ok()) {
    ExpectOnlyFieldErrors([&] { server::VehicleFromProto(vehicle).Validate(); });
  }
  v1::SoilTable soils;
  if (google::protobuf::util::JsonStringToMessage(json, &soils, options).ok()) {
    ExpectOnlyFieldErrors([&] { server::SoilTableOf(soils); });
  }
  return 0;
}
