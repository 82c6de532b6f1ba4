// --suite host: the host's stages on a frame made on the host (engine/bench/host_bench.hpp).
#include "cli/bench_suites.hpp"
#include "cli/scene_argument.hpp"
#include "engine/bench/host_bench.hpp"

#include <cstdio>

namespace vkray::cli {

// --suite host: the host's stages alone on a frame made on the host, at --size: no device is opened.
int run_host_stages(const BenchOptions& options, const std::vector<BenchScene>&) {
  const auto [width, height] = parse_size(options.size);
  std::fputs(host_stages_table(bench_host_stages(width, height, options.frames), width, height).c_str(), stdout);
  return 0;
}

}  // namespace vkray::cli
