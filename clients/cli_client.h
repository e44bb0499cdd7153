// What every `gonogo` command shares: the connection to gonogo-server, following a job with a
// progress bar, reading the files a command line names, and the exit codes.
#pragma once

#include <google/protobuf/util/json_util.h>
#include <grpcpp/grpcpp.h>

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "gonogo/v1/mobility.grpc.pb.h"

namespace gonogo::cli {

namespace v1 = ::gonogo::v1;

// Exit codes of `gonogo`.
inline constexpr int kExitOk = 0;
inline constexpr int kExitJobFailed = 1;  // the job ended FAILED or CANCELLED
inline constexpr int kExitUsage = 2;      // the command line, or a file it names, is wrong
inline constexpr int kExitServer = 3;     // the server refused or could not be reached

// The command line or a file it names is wrong; the message names the option or file.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The bytes of `path`; throws UsageError naming `what` when it cannot be read.
std::string ReadFile(const std::string& path, const std::string& what);

// A message from a JSON file in the proto's JSON form; unknown fields are errors (a misspelt
// field must not pass silently). Throws UsageError naming `what`, the file and the field.
template <typename Message>
Message ReadJson(const std::string& path, const std::string& what) {
  Message m;
  google::protobuf::util::JsonParseOptions opts;
  opts.ignore_unknown_fields = false;
  const auto status = google::protobuf::util::JsonStringToMessage(ReadFile(path, what), &m, opts);
  if (!status.ok()) throw UsageError(what + " " + path + ": " + std::string(status.message()));
  return m;
}

// Shortest form of a number ("0.293", "1.5e+09", "inf").
std::string FormatNumber(double value);

// Prints "gonogo: CODE: message" on stderr; returns kExitServer.
int Fail(const grpc::Status& s);

// "QUEUED", "RUNNING", "DONE", "FAILED", "CANCELLED" or "UNKNOWN".
const char* StateName(v1::JobState s);

// Where the server is and how to talk to it.
struct Connection {
  std::string endpoint;  // HOST:PORT
  std::string token;     // bearer token; empty: none sent
  // TLS: the CA that signed the server's certificate (empty: plaintext), and this client's
  // certificate and key for a server that requires them.
  std::string tls_ca, tls_cert, tls_key;
};

// `--server` as given: "@FILE" is an endpoint file (gonogo-server --endpoint-file), whose first line
// is HOST:PORT and whose optional second line is a bearer token; anything else is HOST:PORT.
// Fills `connection`'s endpoint, and its token when the file has one and `connection` has none.
void ResolveServer(const std::string& server, Connection* connection);

// A connection to one gonogo-server.
class Client {
 public:
  explicit Client(const Connection& connection);

  // Follows the job with a progress bar on stderr until it ends; `last` gets its final status.
  grpc::Status Watch(const std::string& id, v1::JobStatus* last);

  // Writes a finished job's products into `out_dir` (created when missing); `written` gets the
  // paths.
  grpc::Status Download(const std::string& id, const std::string& out_dir,
                        std::vector<std::string>* written);
  // Writes a dataset's export (ExportDataset) into `out_dir`, as Download does.
  grpc::Status ExportDataset(const v1::ExportDatasetRequest& request, const std::string& out_dir,
                             std::vector<std::string>* written);

  // Watches the job and, when it ends other than DONE, says so on stderr. Returns kExitOk when it
  // is DONE, kExitJobFailed when it failed or was cancelled, kExitServer when watching failed.
  // `what` names the job in the message ("job", "curve job").
  int WaitUntilDone(const std::string& id, const std::string& what);

  // WaitUntilDone, then the finished job's summary_json parsed into `summary` (a curve job's
  // TractionCurve, a training job's SurrogateModel). Returns kExitOk, or the exit code after saying
  // why on stderr.
  int WaitForSummary(const std::string& id, const std::string& what,
                     google::protobuf::Message* summary);

  v1::MobilityService::Stub& stub() { return *stub_; }
  // The channel, for gRPC's standard services (health).
  const std::shared_ptr<grpc::Channel>& channel() const { return channel_; }

 private:
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::MobilityService::Stub> stub_;
};

}  // namespace gonogo::cli
