// libFuzzer target: Modbus/TCP Security clients by role. The input is the
// byte stream a client sends on one connection after its TLS handshake (the
// same MBAP framing loop as fuzz_tcp_request, mbap_input.hpp), played as a
// client whose certificate names the role viewer and as one that names
// operator (server/client_role.hpp). Besides "no crash" and the request
// invariants of fuzz_common.hpp: a viewer gets no write accepted; an operator
// changes no setting and gets no write to the simulator unit accepted.
#include <array>
#include <cstddef>
#include <cstdint>

#include "mbap_input.hpp"

namespace {

std::array<fuzz::Harness, 2>& services() {
  using fuzz::Harness;
  static std::array<Harness, 2> s{Harness(Harness::Access::viewer), Harness(Harness::Access::operator_role)};
  return s;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) { return fuzz::initialize(services); }

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return fuzz::play_connection(data, size, services());
}
