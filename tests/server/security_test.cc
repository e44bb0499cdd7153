// Identity and isolation against a real gonogo-server: bearer tokens on every RPC, jobs private to
// the identity that submitted them (NOT_FOUND for anyone else, everything for an admin), the shared
// curve cache, files private whatever the umask, TLS with and without client certificates, and the
// start-up refusals that keep a server from being exposed by mistake.
#include <grpcpp/generic/generic_stub.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>

#include "clients/bearer_token.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "server_process.h"

namespace gonogo::testing {
namespace {

// Calls `method` of the MobilityService with an empty request, as a unary call whatever its kind:
// a refusal before the handler reads anything looks the same for every kind.
grpc::Status CallWithEmptyRequest(const std::shared_ptr<grpc::Channel>& channel,
                                  const std::string& method) {
  grpc::GenericStub stub(channel);
  grpc::CompletionQueue queue;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(20));
  grpc::Slice empty("");
  const grpc::ByteBuffer request(&empty, 1);
  auto call = stub.PrepareUnaryCall(&context, "/gonogo.v1.MobilityService/" + method, request, &queue);
  call->StartCall();
  grpc::ByteBuffer response;
  grpc::Status status;
  call->Finish(&response, &status, reinterpret_cast<void*>(1));
  void* tag = nullptr;
  bool ok = false;
  queue.Next(&tag, &ok);
  queue.Shutdown();
  while (queue.Next(&tag, &ok)) {
  }
  return status;
}

v1::GetTractionCurveRequest EmpiricalCurve(double wheel_load_n) {
  v1::GetTractionCurveRequest request;
  request.set_tier("empirical");
  *request.mutable_tyre() = FedAlpha().axles(0).tyre();
  request.set_wheel_load_n(wheel_load_n);
  request.mutable_soil()->set_cone_index_pa(600e3);
  return request;
}

// The job ids `stub` sees in ListJobs.
std::set<std::string> ListedJobs(v1::MobilityService::Stub& stub) {
  grpc::ClientContext context;
  v1::ListJobsRequest request;
  request.set_limit(1000);
  v1::ListJobsResponse response;
  EXPECT_TRUE(stub.ListJobs(&context, request, &response).ok());
  std::set<std::string> ids;
  for (const auto& job : response.jobs()) ids.insert(job.job_id());
  return ids;
}

TEST(SecurityTest, EveryRpcNeedsAKnownTokenAndHealthNeedsNone) {
  ScratchDir scratch("security-rpcs");
  ServerProcess server(scratch.path() / "data", {"--token-file", WriteTokenFile(scratch.path()).string()});
  EXPECT_NE(server.banner().find("bearer tokens for 3 identities"), std::string::npos) << server.banner();

  const auto* service = v1::MapRequest::descriptor()->file()->FindServiceByName("MobilityService");
  ASSERT_NE(service, nullptr);
  ASSERT_GE(service->method_count(), 16);
  for (int i = 0; i < service->method_count(); ++i) {
    const std::string method = service->method(i)->name();
    for (const std::string& token : {std::string(), std::string("not-a-token-of-this-server")}) {
      const grpc::Status status = CallWithEmptyRequest(server.Channel(token), method);
      EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED)
          << method << " with token '" << token << "': " << status.error_message();
      EXPECT_EQ(status.error_message().find(kAliceToken), std::string::npos);
    }
  }
  // A token is not accepted in another scheme.
  {
    auto stub = server.Stub();
    grpc::ClientContext context;
    context.AddMetadata("authorization", std::string("Basic ") + kAliceToken);
    v1::ListTiersResponse tiers;
    EXPECT_EQ(stub->ListTiers(&context, {}, &tiers).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  }
  // With a known token the same calls reach their handlers.
  EXPECT_TRUE(CallWithEmptyRequest(server.Channel(kBobToken), "ListTiers").ok());
  const grpc::Status watch = CallWithEmptyRequest(server.Channel(kBobToken), "GetJob");
  EXPECT_EQ(watch.error_code(), grpc::StatusCode::NOT_FOUND) << watch.error_message();

  // Health is for schedulers and load balancers, which hold no token.
  auto health = grpc::health::v1::Health::NewStub(server.Channel());
  grpc::ClientContext context;
  grpc::health::v1::HealthCheckRequest request;
  request.set_service("gonogo.v1.MobilityService");
  grpc::health::v1::HealthCheckResponse response;
  ASSERT_TRUE(health->Check(&context, request, &response).ok());
  EXPECT_EQ(response.status(), grpc::health::v1::HealthCheckResponse::SERVING);
}

TEST(SecurityTest, JobsArePrivateToTheirOwnerAndVisibleToAnAdminWhileCurvesAreShared) {
  ScratchDir scratch("security-owners");
  ServerProcess server(scratch.path() / "data", {"--token-file", WriteTokenFile(scratch.path()).string()});
  auto alice = server.Stub(kAliceToken);
  auto bob = server.Stub(kBobToken);
  auto ops = server.Stub(kOpsToken);

  v1::Job job;
  {
    grpc::ClientContext context;
    ASSERT_TRUE(alice->SubmitCurve(&context, EmpiricalCurve(7321.0), &job).ok());
  }
  EXPECT_EQ(job.owner(), "alice");
  EXPECT_EQ(WaitForEnd(*alice, job.job_id()).state(), v1::JOB_STATE_DONE);

  // Bob is told exactly what an unknown id would tell him.
  const std::string unknown_id = "j-does-not-exist";
  for (const std::string& id : {job.job_id(), unknown_id}) {
    const std::string expected = "job_id: no job '" + id + "'";
    v1::GetJobRequest get;
    get.set_job_id(id);
    v1::Job seen;
    grpc::ClientContext c1;
    grpc::Status s = bob->GetJob(&c1, get, &seen);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::NOT_FOUND);
    EXPECT_EQ(s.error_message(), expected);

    v1::CancelJobRequest cancel;
    cancel.set_job_id(id);
    grpc::ClientContext c2;
    s = bob->CancelJob(&c2, cancel, &seen);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::NOT_FOUND);
    EXPECT_EQ(s.error_message(), expected);

    v1::WatchJobRequest watch;
    watch.set_job_id(id);
    grpc::ClientContext c3;
    auto watcher = bob->WatchJob(&c3, watch);
    v1::JobStatus status;
    EXPECT_FALSE(watcher->Read(&status));
    s = watcher->Finish();
    EXPECT_EQ(s.error_code(), grpc::StatusCode::NOT_FOUND);
    EXPECT_EQ(s.error_message(), expected);

    v1::DownloadResultRequest download;
    download.set_job_id(id);
    grpc::ClientContext c4;
    auto reader = bob->DownloadResult(&c4, download);
    v1::ResultChunk chunk;
    EXPECT_FALSE(reader->Read(&chunk));
    s = reader->Finish();
    EXPECT_EQ(s.error_code(), grpc::StatusCode::NOT_FOUND);
    EXPECT_EQ(s.error_message(), expected);
  }
  EXPECT_EQ(ListedJobs(*bob).count(job.job_id()), 0u);
  EXPECT_EQ(ListedJobs(*alice).count(job.job_id()), 1u);
  EXPECT_EQ(ListedJobs(*ops).count(job.job_id()), 1u);
  {
    v1::GetJobRequest get;
    get.set_job_id(job.job_id());
    v1::Job seen;
    grpc::ClientContext context;
    ASSERT_TRUE(ops->GetJob(&context, get, &seen).ok());
    EXPECT_EQ(seen.owner(), "alice");
  }
  EXPECT_EQ(NamesOf(DownloadAll(*alice, job.job_id())).count("curve.json"), 1u);

  // The curve alice's job computed is physics, not alice's data: bob's query is a cache hit.
  v1::TractionCurve curve;
  grpc::ClientContext context;
  ASSERT_TRUE(bob->GetTractionCurve(&context, EmpiricalCurve(7321.0), &curve).ok());
  EXPECT_TRUE(curve.provenance().cache_hit());

  // The command line carries a token too, and an admin's list says whose each job is.
  {
    v1::Job mine;
    grpc::ClientContext c;
    ASSERT_TRUE(bob->SubmitCurve(&c, EmpiricalCurve(7322.0), &mine).ok());
    WaitForEnd(*bob, mine.job_id());
  }
  const CliRun as_ops = Gonogo(server.endpoint(), std::string("--token ") + kOpsToken + " jobs");
  EXPECT_EQ(as_ops.exit_code, 0) << as_ops.out;
  EXPECT_NE(as_ops.out.find("alice: "), std::string::npos) << as_ops.out;
  EXPECT_NE(as_ops.out.find("bob: "), std::string::npos) << as_ops.out;
  const CliRun anonymous = Gonogo(server.endpoint(), "jobs");
  EXPECT_EQ(anonymous.exit_code, 3) << anonymous.out;
  EXPECT_NE(anonymous.out.find("UNAUTHENTICATED"), std::string::npos) << anonymous.out;
}

// A curve query for the tyre of EmpiricalCurve scaled by `k` in every length, its load by k^2: the
// same pi-terms, so that a stored curve of the other size answers it by similarity (seed 001).
v1::GetTractionCurveRequest ScaledEmpiricalCurve(double wheel_load_n, double k) {
  v1::GetTractionCurveRequest request = EmpiricalCurve(wheel_load_n * k * k);
  v1::Tyre* t = request.mutable_tyre();
  t->set_diameter_m(t->diameter_m() * k);
  t->set_width_m(t->width_m() * k);
  t->set_section_height_m(t->section_height_m() * k);
  t->set_deflection_m(t->deflection_m() * k);
  return request;
}

v1::Provenance CurveProvenance(v1::MobilityService::Stub& stub, const v1::GetTractionCurveRequest& request) {
  grpc::ClientContext context;
  v1::TractionCurve curve;
  const grpc::Status s = stub.GetTractionCurve(&context, request, &curve);
  EXPECT_TRUE(s.ok()) << s.error_message();
  return curve.provenance();
}


TEST(SecurityTest, WithPrivateCurvesNoIdentityIsAnsweredFromAnothersCurves) {
  ScratchDir scratch("security-private-curves");
  ServerProcess server(scratch.path() / "data",
                       {"--token-file", WriteTokenFile(scratch.path()).string(), "--private-curves"});
  auto alice = server.Stub(kAliceToken);
  auto bob = server.Stub(kBobToken);
  auto ops = server.Stub(kOpsToken);
  EXPECT_FALSE(CurveProvenance(*alice, EmpiricalCurve(7321.0)).cache_hit());
  // Alice's own cache answers her, exactly and by similarity.
  EXPECT_TRUE(CurveProvenance(*alice, EmpiricalCurve(7321.0)).cache_hit());
  const v1::Provenance similar = CurveProvenance(*alice, ScaledEmpiricalCurve(7321.0, 0.8));
  EXPECT_TRUE(similar.cache_hit() && similar.similarity_hit()) << similar.ShortDebugString();
  // Bob's queries are computed for him, neither from alice's curve nor scaled from it.
  EXPECT_FALSE(CurveProvenance(*bob, ScaledEmpiricalCurve(7321.0, 0.8)).cache_hit());
  v1::GetTractionCurveRequest exact = EmpiricalCurve(7321.0);
  exact.set_disable_similarity(true);  // not from his own scaled curve either
  EXPECT_FALSE(CurveProvenance(*bob, exact).cache_hit());
  EXPECT_TRUE(CurveProvenance(*bob, exact).cache_hit());
  // Each lists its own; the admin lists both.
  EXPECT_EQ(CurveCount(*alice), 1);
  EXPECT_EQ(CurveCount(*bob), 2);
  EXPECT_EQ(CurveCount(*ops), 3);
}

// Every directory under `root` is 0700 and every file 0600 or stricter; returns the offenders.
std::vector<std::string> NotPrivate(const fs::path& root) {
  std::vector<std::string> offenders;
  const auto check = [&](const fs::path& p) {
    struct stat st {};
    if (lstat(p.c_str(), &st) == 0 && (st.st_mode & 077) != 0) {
      offenders.push_back(p.string() + " mode " + std::to_string(st.st_mode & 0777));
    }
  };
  check(root);
  for (const auto& entry : fs::recursive_directory_iterator(root)) check(entry.path());
  return offenders;
}

TEST(SecurityTest, EverythingTheServerWritesIsPrivateWhateverTheUmask) {
  ScratchDir scratch("security-files");
  ASSERT_TRUE(MakeSampleTerrain(scratch.path() / "terrain", 24));
  const fs::path data = scratch.path() / "data";
  fs::create_directories(data);
  fs::permissions(data, fs::perms::all);  // 0777, as a careless mkdir might leave it
  const fs::path endpoint_file = scratch.path() / "endpoint";
  const mode_t previous = umask(0);  // the server inherits the most permissive umask there is
  std::unique_ptr<ServerProcess> server;
  try {
    server = std::make_unique<ServerProcess>(
        data, std::vector<std::string>{"--generate-token", "--endpoint-file", endpoint_file.string()});
  } catch (...) {
    umask(previous);
    throw;
  }
  umask(previous);

  // The endpoint file: the address, then the generated token of the user who started the server.
  struct stat st {};
  ASSERT_EQ(stat(endpoint_file.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  std::ifstream lines(endpoint_file);
  std::string endpoint, token;
  std::getline(lines, endpoint);
  std::getline(lines, token);
  EXPECT_EQ(endpoint, server->endpoint());
  EXPECT_EQ(token.size(), 64u);
  EXPECT_EQ(token.find_first_not_of("0123456789abcdef"), std::string::npos);

  // A map through the endpoint file alone (the CLI reads the token from it), so that inputs,
  // products, the database and its WAL all exist.
  const fs::path terrain = scratch.path() / "terrain";
  const CliRun map = Gonogo(
      "@" + endpoint_file.string(),
      "map --tier empirical --cone-index " + (terrain / "cone_index.tif").string() + " --elevation " +
          (terrain / "elevation.tif").string() + " --soil-class " + (terrain / "soil_class.tif").string() +
          " --soil-table " + (terrain / "soil_table.json").string() + " --vehicle " + SourceDir() +
          "/clients/vehicles/fed_alpha.json --out " + (scratch.path() / "out").string());
  ASSERT_EQ(map.exit_code, 0) << map.out;
  EXPECT_TRUE(fs::exists(data / "gonogo.sqlite-wal"));
  EXPECT_EQ(NotPrivate(data), std::vector<std::string>{});
  ASSERT_EQ(server->Terminate(), 0);
}

TEST(SecurityTest, AServerOthersCouldReachMustBeToldHowToProtectItself) {
  ScratchDir scratch("security-refusals");
  const fs::path tokens = WriteTokenFile(scratch.path());
  const std::string server = BinaryDir() + "/server/gonogo-server --data-dir " +
                             (scratch.path() / "data").string() + " ";
  CliRun run = RunShell(server + "--listen 0.0.0.0:0");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.out.find("--token-file or --generate-token"), std::string::npos) << run.out;
  run = RunShell(server + "--listen 0.0.0.0:0 --token-file " + tokens.string());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.out.find("--tls-cert"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("--allow-plaintext-network"), std::string::npos) << run.out;

  fs::permissions(tokens, fs::perms::group_read | fs::perms::others_read, fs::perm_options::add);
  run = RunShell(server + "--listen 127.0.0.1:0 --token-file " + tokens.string());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.out.find("lets other users read it"), std::string::npos) << run.out;

  const fs::path bad = scratch.path() / "bad-tokens";
  std::ofstream(bad) << "short alice\n";
  fs::permissions(bad, fs::perms::owner_read | fs::perms::owner_write);
  run = RunShell(server + "--listen 127.0.0.1:0 --token-file " + bad.string());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.out.find("line 1: a token must have at least 16 characters"), std::string::npos) << run.out;

  run = RunShell(server + "--listen 127.0.0.1:0 --generate-token");
  EXPECT_EQ(run.exit_code, 2) << "a generated token nobody can read is a usage error";
  EXPECT_NE(run.out.find("--endpoint-file"), std::string::npos) << run.out;
  EXPECT_FALSE(fs::exists(scratch.path() / "data" / "gonogo.sqlite")) << "refused before touching data";
}

TEST(SecurityTest, AnUploadBeyondTheLimitIsRefusedNamingTheLimitAndLeavesNothing) {
  ScratchDir scratch("security-upload");
  ASSERT_TRUE(MakeSampleTerrain(scratch.path() / "terrain", 24));
  ServerProcess server(scratch.path() / "data", {"--max-upload-mib", "1"});
  auto stub = server.Stub();
  v1::MapRequest request;
  request.set_name("too big");
  request.set_tier("empirical");
  *request.mutable_vehicle() = FedAlpha();
  const std::string two_mib(2 << 20, '\0');
  v1::Job job;
  const grpc::Status s = Submit(*stub, request, {{v1::RASTER_ROLE_CONE_INDEX, two_mib}}, &job);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_NE(s.error_message().find("1 MiB (gonogo-server --max-upload-mib)"), std::string::npos)
      << s.error_message();
  EXPECT_TRUE(fs::is_empty(scratch.path() / "data" / "jobs"));
  EXPECT_TRUE(ListedJobs(*stub).empty());
}

// A self-signed certificate for 127.0.0.1 (its own CA) and its key, made with openssl.
void MakeCertificate(const fs::path& dir, const std::string& name) {
  const CliRun made = RunShell("openssl req -x509 -newkey rsa:2048 -nodes -days 2 -subj /CN=" + name +
                               " -addext subjectAltName=IP:127.0.0.1 -keyout " +
                               (dir / (name + ".key")).string() + " -out " +
                               (dir / (name + ".pem")).string() + " 2>&1");
  ASSERT_EQ(made.exit_code, 0) << made.out;
}

std::unique_ptr<v1::MobilityService::Stub> TlsStub(const std::string& endpoint, const fs::path& dir,
                                                    const std::string& token, bool client_certificate) {
  grpc::SslCredentialsOptions ssl;
  ssl.pem_root_certs = ReadFile(dir / "server.pem");
  if (client_certificate) {
    ssl.pem_cert_chain = ReadFile(dir / "client.pem");
    ssl.pem_private_key = ReadFile(dir / "client.key");
  }
  return v1::MobilityService::NewStub(
      clients::ChannelWithToken(endpoint, grpc::SslCredentials(ssl), token));
}

grpc::Status ListTiers(v1::MobilityService::Stub& stub) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  v1::ListTiersResponse response;
  return stub.ListTiers(&context, {}, &response);
}

TEST(SecurityTest, TlsCarriesTheTokensAndCanRequireClientCertificates) {
  ScratchDir scratch("security-tls");
  const fs::path dir = scratch.path();
  MakeCertificate(dir, "server");
  MakeCertificate(dir, "client");
  const std::string tokens = WriteTokenFile(dir).string();
  {
    ServerProcess server(dir / "data", {"--token-file", tokens, "--tls-cert", (dir / "server.pem").string(),
                                        "--tls-key", (dir / "server.key").string()});
    EXPECT_NE(server.banner().find("; TLS, bearer tokens"), std::string::npos) << server.banner();
    EXPECT_TRUE(ListTiers(*TlsStub(server.endpoint(), dir, kAliceToken, false)).ok());
    EXPECT_EQ(ListTiers(*TlsStub(server.endpoint(), dir, "", false)).error_code(),
              grpc::StatusCode::UNAUTHENTICATED);
    EXPECT_FALSE(ListTiers(*server.Stub(kAliceToken)).ok()) << "plaintext is not served";
    const CliRun cli = Gonogo(server.endpoint(), "--tls-ca " + (dir / "server.pem").string() +
                                                     " --token " + kAliceToken + " tiers");
    EXPECT_EQ(cli.exit_code, 0) << cli.out;
    EXPECT_NE(cli.out.find("empirical"), std::string::npos) << cli.out;
  }
  {
    ServerProcess server(dir / "data", {"--token-file", tokens, "--tls-cert", (dir / "server.pem").string(),
                                        "--tls-key", (dir / "server.key").string(), "--tls-client-ca",
                                        (dir / "client.pem").string()});
    EXPECT_NE(server.banner().find("TLS with client certificates"), std::string::npos) << server.banner();
    EXPECT_TRUE(ListTiers(*TlsStub(server.endpoint(), dir, kAliceToken, true)).ok());
    EXPECT_FALSE(ListTiers(*TlsStub(server.endpoint(), dir, kAliceToken, false)).ok());
  }
}

}  // namespace
}  // namespace gonogo::testing
