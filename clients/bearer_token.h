// A gRPC channel whose every call carries "authorization: Bearer TOKEN", the identity
// gonogo-server checks (server/identity.h). gRPC's call credentials would send it over TLS only;
// the server takes the same header over plaintext loopback, so one interceptor serves both.
#pragma once

#include <grpcpp/grpcpp.h>

#include <memory>
#include <string>

namespace gonogo::clients {

// `token` empty: a plain channel.
std::shared_ptr<grpc::Channel> ChannelWithToken(const std::string& endpoint,
                                                std::shared_ptr<grpc::ChannelCredentials> credentials,
                                                const std::string& token);

}  // namespace gonogo::clients
