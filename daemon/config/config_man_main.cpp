// SPDX-License-Identifier: Apache-2.0
// weedspray-config-man VERSION: prints the man page weedspray.toml(5), in roff, from the key
// table (a build step; not installed).
#include <iostream>

#include "daemon/config/config_schema.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: weedspray-config-man VERSION\n";
    return 2;
  }
  std::cout << weedspray::daemon::config_reference_man(argv[1]);
  return std::cout ? 0 : 1;
}
