#include "clients/cli_client.h"

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "clients/bearer_token.h"

namespace gonogo::cli {
namespace {

namespace fs = std::filesystem;

// Progress on stderr: a redrawn bar on a terminal, a line per 10 % (or new state) otherwise.
class ProgressBar {
 public:
  ProgressBar() : tty_(isatty(STDERR_FILENO)) {}

  void Show(const v1::JobStatus& s) {
    const int percent = static_cast<int>(std::floor(100 * s.fraction_done()));
    const int filled = percent * 30 / 100;
    std::ostringstream line;
    line << "[" << std::string(filled, '#') << std::string(30 - filled, '-') << "] " << std::setw(3)
         << percent << "%  tasks " << s.tasks_done() << "/" << s.tasks_total() << "  cache hits "
         << s.cache_hits() << "  similar " << s.similarity_hits() << "  " << StateName(s.state())
         << ": " << s.message();
    if (tty_) {
      std::cerr << "\r\033[K" << line.str() << std::flush;
    } else if (percent / 10 != last_decile_ || s.state() != last_state_) {
      std::cerr << line.str() << "\n";
    }
    last_decile_ = percent / 10;
    last_state_ = s.state();
  }

  void Done() {
    if (tty_) std::cerr << "\n";
  }

 private:
  bool tty_;
  int last_decile_ = -1;
  v1::JobState last_state_ = v1::JOB_STATE_UNSPECIFIED;
};

// Only plain file names are accepted from the server.
bool IsPlainFileName(const std::string& name) {
  return !name.empty() && name.find('/') == std::string::npos && name[0] != '.';
}

}  // namespace

std::string FormatNumber(double value) {
  std::ostringstream out;
  out << std::setprecision(6) << value;
  return out.str();
}

std::string ReadFile(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw UsageError(what + ": cannot read " + path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

int Fail(const grpc::Status& s) {
  static const char* kNames[] = {"OK",
                                 "CANCELLED",
                                 "UNKNOWN",
                                 "INVALID_ARGUMENT",
                                 "DEADLINE_EXCEEDED",
                                 "NOT_FOUND",
                                 "ALREADY_EXISTS",
                                 "PERMISSION_DENIED",
                                 "RESOURCE_EXHAUSTED",
                                 "FAILED_PRECONDITION",
                                 "ABORTED",
                                 "OUT_OF_RANGE",
                                 "UNIMPLEMENTED",
                                 "INTERNAL",
                                 "UNAVAILABLE",
                                 "DATA_LOSS",
                                 "UNAUTHENTICATED"};
  const int code = static_cast<int>(s.error_code());
  std::cerr << "gonogo: " << (code >= 0 && code <= 16 ? kNames[code] : "ERROR") << ": "
            << s.error_message() << "\n";
  return kExitServer;
}

const char* StateName(v1::JobState s) {
  switch (s) {
    case v1::JOB_STATE_QUEUED:
      return "QUEUED";
    case v1::JOB_STATE_RUNNING:
      return "RUNNING";
    case v1::JOB_STATE_DONE:
      return "DONE";
    case v1::JOB_STATE_FAILED:
      return "FAILED";
    case v1::JOB_STATE_CANCELLED:
      return "CANCELLED";
    default:
      return "UNKNOWN";
  }
}

namespace {

std::shared_ptr<grpc::Channel> OpenChannel(const Connection& c) {
  std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials();
  if (!c.tls_ca.empty()) {
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = ReadFile(c.tls_ca, "--tls-ca");
    if (!c.tls_cert.empty()) ssl.pem_cert_chain = ReadFile(c.tls_cert, "--tls-cert");
    if (!c.tls_key.empty()) ssl.pem_private_key = ReadFile(c.tls_key, "--tls-key");
    credentials = grpc::SslCredentials(ssl);
  }
  return clients::ChannelWithToken(c.endpoint, credentials, c.token);
}

}  // namespace

void ResolveServer(const std::string& server, Connection* connection) {
  if (server.empty() || server[0] != '@') {
    connection->endpoint = server;
    return;
  }
  std::istringstream lines(ReadFile(server.substr(1), "endpoint file"));
  std::string endpoint, token;
  std::getline(lines, endpoint);
  std::getline(lines, token);
  const auto trim = [](std::string& s) {
    s.erase(s.find_last_not_of(" \n\r\t") + 1);
    s.erase(0, s.find_first_not_of(" \t"));
  };
  trim(endpoint);
  trim(token);
  if (endpoint.empty()) throw UsageError("endpoint file " + server.substr(1) + " holds no HOST:PORT");
  connection->endpoint = endpoint;
  if (connection->token.empty()) connection->token = token;
}

Client::Client(const Connection& connection)
    : channel_(OpenChannel(connection)), stub_(v1::MobilityService::NewStub(channel_)) {}

grpc::Status Client::Watch(const std::string& id, v1::JobStatus* last) {
  ProgressBar bar;
  grpc::ClientContext ctx;
  v1::WatchJobRequest req;
  req.set_job_id(id);
  auto reader = stub_->WatchJob(&ctx, req);
  v1::JobStatus s;
  while (reader->Read(&s)) {
    bar.Show(s);
    *last = s;
  }
  bar.Done();
  return reader->Finish();
}

namespace {

// Writes the streamed files into `out_dir` (created when missing), one file per name.
grpc::Status ReceiveFiles(grpc::ClientReader<v1::ResultChunk>& reader, const std::string& out_dir,
                          std::vector<std::string>* written) {
  fs::create_directories(out_dir);
  v1::ResultChunk chunk;
  std::ofstream out;
  std::string current;
  while (reader.Read(&chunk)) {
    if (chunk.product() != current) {
      out.close();
      current = chunk.product();
      if (!IsPlainFileName(current)) {
        return {grpc::StatusCode::INTERNAL, "server sent a bad file name"};
      }
      out.open(fs::path(out_dir) / current, std::ios::binary | std::ios::trunc);
      written->push_back((fs::path(out_dir) / current).string());
    }
    out.write(chunk.data().data(), static_cast<std::streamsize>(chunk.data().size()));
  }
  return reader.Finish();
}

}  // namespace

grpc::Status Client::Download(const std::string& id, const std::string& out_dir,
                              std::vector<std::string>* written) {
  grpc::ClientContext ctx;
  v1::DownloadResultRequest req;
  req.set_job_id(id);
  auto reader = stub_->DownloadResult(&ctx, req);
  return ReceiveFiles(*reader, out_dir, written);
}

grpc::Status Client::ExportDataset(const v1::ExportDatasetRequest& request,
                                   const std::string& out_dir, std::vector<std::string>* written) {
  grpc::ClientContext ctx;
  auto reader = stub_->ExportDataset(&ctx, request);
  return ReceiveFiles(*reader, out_dir, written);
}

int Client::WaitUntilDone(const std::string& id, const std::string& what) {
  v1::JobStatus last;
  const grpc::Status watched = Watch(id, &last);
  if (!watched.ok()) return Fail(watched);
  if (last.state() == v1::JOB_STATE_DONE) return kExitOk;
  std::cerr << "gonogo: " << what << " " << id << " " << StateName(last.state()) << ": "
            << last.message() << "\n";
  return kExitJobFailed;
}

int Client::WaitForSummary(const std::string& id, const std::string& what,
                           google::protobuf::Message* summary) {
  if (const int rc = WaitUntilDone(id, what); rc != kExitOk) return rc;
  grpc::ClientContext ctx;
  v1::GetJobRequest get;
  get.set_job_id(id);
  v1::Job done;
  const grpc::Status s = stub_->GetJob(&ctx, get, &done);
  if (!s.ok()) return Fail(s);
  if (!google::protobuf::util::JsonStringToMessage(done.summary_json(), summary).ok()) {
    std::cerr << "gonogo: the server's summary of " << what << " " << id << " is unreadable\n";
    return kExitServer;
  }
  return kExitOk;
}

}  // namespace gonogo::cli
