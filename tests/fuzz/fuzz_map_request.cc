// libFuzzer target: the request messages. The bytes are a serialised SubmitMapRequest's first
// message (or a curve query); what the service does with one before anything is stored runs on
// them: the string bounds, the vehicle, the criteria, the soil table, a curve query's tyre, load,
// soil and slip sweep.
#include <cstddef>
#include <cstdint>

#include "fuzz_expected.h"
#include "server/request_convert.h"

using namespace gonogo;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  v1::SubmitMapRequest message;
  if (message.ParseFromArray(data, static_cast<int>(size)) && message.has_request()) {
    const v1::MapRequest& request = message.request();
    ExpectOnlyFieldErrors([&] { server::RequireShortNames(request); });
    ExpectOnlyFieldErrors([&] { server::VehicleFromProto(request.vehicle()).Validate(); });
    ExpectOnlyFieldErrors([&] { server::CriteriaFromProto(request.criteria()); });
    ExpectOnlyFieldErrors([&] { server::SoilTableOf(request.soil_table()); });
  }
  v1::GetTractionCurveRequest curve;
  if (curve.ParseFromArray(data, static_cast<int>(size))) {
    ExpectOnlyFieldErrors([&] { server::FromProto(curve).Validate(); });
  }
  return 0;
}
