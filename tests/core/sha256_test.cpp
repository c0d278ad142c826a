// SHA-256 against the test vectors of FIPS 180-2 (Appendix B) and NIST's
// examples; the file digest against the same vector spread over blocks.
#include "core/sha256.h"

#include <catch2/catch.hpp>
#include <stdexcept>
#include <string>

#include "test_support.h"

using uavsim::core::Sha256FileHex;
using uavsim::core::Sha256Hex;

TEST_CASE("Sha256Hex: FIPS 180-2 test vectors", "[core]") {
  CHECK(Sha256Hex("") == "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  CHECK(Sha256Hex("abc") == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  CHECK(Sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq") ==
        "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
}

TEST_CASE("Sha256FileHex: one million 'a' read in blocks; unreadable files named", "[core]") {
  const std::string dir = uavsim::testing::TempDir("sha256");
  uavsim::testing::WriteFile(dir + "/a", std::string(1000000, 'a'));  // 15+ blocks of 64 KiB
  CHECK(Sha256FileHex(dir + "/a") ==
        "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  CHECK_THROWS_WITH(Sha256FileHex(dir + "/none"), dir + "/none: cannot read");
}
