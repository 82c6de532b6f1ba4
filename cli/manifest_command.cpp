#include "cli/commands.hpp"
#include "engine/io/image_io.hpp"
#include "engine/views/manifest.hpp"

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace vkray::cli {

Action add_manifest_command(CLI::App& app) {
  CLI::App* command = app.add_subcommand("manifest", "Work with the manifests of many-view renders.");
  command->require_subcommand(1);
  CLI::App* merge = command->add_subcommand(
      "merge", "Merge the manifest parts of shards into one manifest, each view once, in index order.");
  auto parts = std::make_shared<std::vector<std::string>>();
  auto output = std::make_shared<std::string>();
  merge->add_option("parts", *parts, "The shards' manifest parts (manifest-shard-*.jsonl)")->required();
  merge->add_option("-o,--output", *output, "The merged manifest, in any folder: its file names are made relative to it")
      ->required();
  return [parts, output] {
    const std::vector<std::filesystem::path> paths(parts->begin(), parts->end());
    const std::string merged = merge_manifests(paths, *output);
    write_text_file(*output, merged);
    size_t views = 0;
    for (char c : merged) views += c == '\n';
    std::printf("vkray: %s holds %zu view%s from %zu part%s\n", output->c_str(), views, views == 1 ? "" : "s", paths.size(),
                paths.size() == 1 ? "" : "s");
    return 0;
  };
}

}  // namespace vkray::cli
