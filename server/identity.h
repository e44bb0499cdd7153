// Who is calling: bearer tokens (`authorization: Bearer TOKEN` metadata) mapped to identities.
//
// An identity owns the jobs it submits; another identity cannot see them, and an admin identity
// can see every job. Tokens come from a token file (one "TOKEN NAME [admin]" per line, the file
// private to the service's user, as ssh requires of its keys) and from one token generated per start
// for the user who started the server (written to the endpoint file; the Slurm allocation's token).
// With no token at all every caller is the one local identity: the laptop mode, which the server
// allows on loopback addresses only.
#pragma once

#include <grpcpp/grpcpp.h>

#include <string>
#include <vector>

namespace gonogo::server {

struct Identity {
  std::string name;
  bool admin = false;
};

// The identity of every caller when no token is configured, and the owner of jobs stored before
// jobs had owners.
inline constexpr char kLocalIdentity[] = "local";
// Tokens shorter than this are refused: a token is a password nobody types.
inline constexpr size_t kMinTokenChars = 16;

class Authenticator {
 public:
  // Reads a token file. Throws std::runtime_error naming the file, and the line and its fault
  // (no name, a short token, a token used twice, an unknown flag), or the file's mode when
  // anyone but its owner may read or write it.
  void LoadTokenFile(const std::string& path);
  // Adds one token for `who`; throws std::runtime_error when it is short or already used.
  void AddToken(const std::string& token, Identity who);

  // True when callers must present a token.
  bool required() const { return !entries_.empty(); }
  // Distinct identities that hold a token.
  int identity_count() const;

  // The caller's identity, or UNAUTHENTICATED (the reason, never a token) when tokens are required
  // and the call carries none or an unknown one.
  grpc::Status Identify(const grpc::ServerContext& context, Identity* who) const;

 private:
  struct Entry {
    std::string token;
    Identity who;
  };
  std::vector<Entry> entries_;
};

// 32 bytes from the system's random source, as 64 hexadecimal digits.
std::string GenerateToken();
// The login name of the user running the process ("uid N" when it has none).
std::string ProcessUserName();
// True for 127.0.0.0/8, ::1 and localhost (brackets allowed).
bool IsLoopbackHost(const std::string& host);

}  // namespace gonogo::server
