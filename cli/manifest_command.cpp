#include "cli/commands.hpp"
#include "engine/io/image_io.hpp"
#include "engine/views/manifest.hpp"
#include "engine/views/manifest_export.hpp"

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
  CLI::App* to_format = command->add_subcommand(
      "export", "Write a manifest's cameras as NeRF's transforms.json or COLMAP's text model (docs/many-views.md).");
  auto manifest = std::make_shared<std::string>();
  auto format = std::make_shared<std::string>();
  auto folder = std::make_shared<std::string>();
  to_format->add_option("manifest", *manifest, "The manifest of a whole run (manifest.jsonl, or a merged one)")->required();
  to_format->add_option("--format", *format, "nerf (transforms.json) or colmap (cameras.txt, images.txt, points3D.txt)")
      ->required();
  to_format->add_option("-o,--output", *folder, "The folder to write them into (made if missing)")->required();
  return [merge, parts, output, manifest, format, folder] {
    if (!merge->parsed()) {
      const auto files = export_manifest(*manifest, manifest_format_from_name(*format), *folder);
      std::filesystem::create_directories(*folder);
      // All the files or none: each is checked before the first is written (a link at images.txt
      // must not leave cameras.txt of this export beside an older images.txt).
      for (const auto& file : files) check_output_path(std::filesystem::path(*folder) / file.first);
      for (const auto& [name, text] : files) write_text_file(std::filesystem::path(*folder) / name, text);
      std::printf("vkray: wrote %zu file%s into %s\n", files.size(), files.size() == 1 ? "" : "s", folder->c_str());
      return 0;
    }
    const std::vector<std::filesystem::path> paths(parts->begin(), parts->end());
    const std::string merged = merge_manifests(paths, *output);
    // As render makes the folders it writes into.
    if (const std::filesystem::path output_folder = std::filesystem::path(*output).parent_path(); !output_folder.empty()) {
      std::filesystem::create_directories(output_folder);
    }
    check_output_path(*output);
    write_text_file(*output, merged);
    size_t views = 0;
    for (char c : merged) views += c == '\n';
    std::printf("vkray: %s holds %zu view%s from %zu part%s\n", output->c_str(), views, views == 1 ? "" : "s", paths.size(),
                paths.size() == 1 ? "" : "s");
    return 0;
  };
}

}  // namespace vkray::cli
