#include "server/identity.h"

#include <pwd.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>

namespace gonogo::server {

namespace {

// Equal strings, in a time that depends on their lengths only, so that a caller cannot learn a
// token a byte at a time from how long a refusal takes.
bool ConstantTimeEqual(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char differ = 0;
  for (size_t i = 0; i < a.size(); ++i) differ |= static_cast<unsigned char>(a[i] ^ b[i]);
  return differ == 0;
}

}  // namespace

void Authenticator::AddToken(const std::string& token, Identity who) {
  if (token.size() < kMinTokenChars) {
    throw std::runtime_error("a token must have at least " + std::to_string(kMinTokenChars) +
                             " characters");
  }
  for (const Entry& e : entries_) {
    if (e.token == token) throw std::runtime_error("the same token is given twice");
  }
  if (who.name.empty()) throw std::runtime_error("a token needs an identity name");
  entries_.push_back({token, std::move(who)});
}

void Authenticator::LoadTokenFile(const std::string& path) {
  struct stat st {};
  if (stat(path.c_str(), &st) != 0) throw std::runtime_error("token file " + path + ": cannot be read");
  if ((st.st_mode & 077) != 0) {
    std::ostringstream mode;
    mode << std::oct << (st.st_mode & 0777);
    throw std::runtime_error("token file " + path + ": mode 0" + mode.str() +
                             " lets other users read it; chmod 600 it");
  }
  std::ifstream in(path);
  if (!in) throw std::runtime_error("token file " + path + ": cannot be read");
  int line_number = 0;
  for (std::string line; std::getline(in, line);) {
    ++line_number;
    const std::string where = "token file " + path + " line " + std::to_string(line_number) + ": ";
    std::istringstream words(line);
    std::string token, name, flag, extra;
    if (!(words >> token) || token[0] == '#') continue;
    if (!(words >> name)) throw std::runtime_error(where + "a token needs an identity name after it");
    Identity who{name, false};
    if (words >> flag) {
      if (flag != "admin") throw std::runtime_error(where + "unknown flag '" + flag + "' (only admin)");
      who.admin = true;
    }
    if (words >> extra) throw std::runtime_error(where + "unexpected '" + extra + "'");
    try {
      AddToken(token, who);
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(where + e.what());
    }
  }
}

int Authenticator::identity_count() const {
  std::set<std::string> names;
  for (const Entry& e : entries_) names.insert(e.who.name);
  return static_cast<int>(names.size());
}

grpc::Status Authenticator::Identify(const grpc::ServerContext& context, Identity* who) const {
  if (entries_.empty()) {
    *who = Identity{kLocalIdentity, false};
    return grpc::Status::OK;
  }
  const auto& metadata = context.client_metadata();
  const auto found = metadata.find("authorization");
  if (found == metadata.end()) {
    return {grpc::StatusCode::UNAUTHENTICATED,
            "authorization: this server needs a bearer token (metadata 'authorization: Bearer "
            "TOKEN'; gonogo --token, or the endpoint file's second line)"};
  }
  const std::string value(found->second.data(), found->second.size());
  constexpr char kScheme[] = "Bearer ";
  if (value.rfind(kScheme, 0) != 0) {
    return {grpc::StatusCode::UNAUTHENTICATED, "authorization: expected 'Bearer TOKEN'"};
  }
  const std::string token = value.substr(sizeof(kScheme) - 1);
  const Entry* match = nullptr;
  for (const Entry& e : entries_) {  // every entry is compared, whatever matched
    if (ConstantTimeEqual(e.token, token)) match = &e;
  }
  if (match == nullptr) return {grpc::StatusCode::UNAUTHENTICATED, "authorization: unknown token"};
  *who = match->who;
  return grpc::Status::OK;
}

std::string GenerateToken() {
  std::random_device source;  // /dev/urandom on Linux
  std::string token;
  constexpr char kHex[] = "0123456789abcdef";
  for (int i = 0; i < 8; ++i) {
    const uint32_t word = source();
    for (int nibble = 0; nibble < 8; ++nibble) token += kHex[(word >> (4 * nibble)) & 0xF];
  }
  return token;
}

std::string ProcessUserName() {
  const uid_t uid = getuid();
  if (const passwd* pw = getpwuid(uid); pw != nullptr && pw->pw_name != nullptr) return pw->pw_name;
  return "uid " + std::to_string(uid);
}

bool IsLoopbackHost(const std::string& host_in) {
  std::string host = host_in;
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

}  // namespace gonogo::server
