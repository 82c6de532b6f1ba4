// Every vkray command the README and the manual's pages (docs/*.md) show in a ```sh block runs and
// exits 0, in their order (the README first, then the pages by file name), each distinct command
// once, in a temporary copy of the layout they assume (build/vkray, ../shared/models, docs/ with its
// bench scenes, a scene.json made of docs/scene-format.md's own scene example). So an option renamed,
// removed or misspelt in the README or a page fails here. To keep the suite short, image sizes are cut to 64x36, the bench to one
// frame of one round and the rays suite to 4096 rays a kind: what this checks is that each
// command is accepted and works, not the figures beside it (those come from the commands as
// printed, re-run by hand). `view` commands run under xvfb-run for
// two frames. The setup and test commands (install-deps, cmake, ctest) are what CI itself runs.
#include "tests/temp_dir_test.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#ifndef VKRAY_BINARY
#error "VKRAY_BINARY comes from CMake"
#endif
#ifndef VKRAY_MODELS_DIR
#error "VKRAY_MODELS_DIR comes from CMake"
#endif

namespace {

namespace fs = std::filesystem;

const fs::path repository = fs::path(__FILE__).parent_path().parent_path();

// The README, then the manual's pages in the order of their names.
std::vector<fs::path> documents() {
  std::vector<fs::path> pages;
  for (const auto& entry : fs::directory_iterator(repository / "docs")) {
    if (entry.is_regular_file() && entry.path().extension() == ".md") pages.push_back(entry.path());
  }
  std::sort(pages.begin(), pages.end());
  pages.insert(pages.begin(), repository / "README.md");
  return pages;
}

std::string read_text(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::ostringstream contents;
  contents << file.rdbuf();
  return contents.str();
}

// The lines of a page's ```sh blocks, trailing comments removed.
std::vector<std::string> shell_lines(const std::string& readme) {
  std::vector<std::string> lines;
  std::istringstream text(readme);
  bool in_block = false;
  for (std::string line; std::getline(text, line);) {
    if (line.starts_with("```")) {
      in_block = !in_block && line == "```sh";
      continue;
    }
    if (!in_block) continue;
    if (const size_t comment = line.find("  #"); comment != std::string::npos) line.resize(comment);
    while (!line.empty() && line.back() == ' ') line.pop_back();
    if (!line.empty()) lines.push_back(line);
  }
  return lines;
}

// The scene-file example: the first ```json block of docs/scene-format.md.
std::string scene_example(const std::string& readme) {
  const size_t start = readme.find("```json\n");
  if (start == std::string::npos) return "";
  const size_t body = start + 8;
  return readme.substr(body, readme.find("```", body) - body);
}

// The command as the test runs it: small images, one bench frame, viewers for two frames on a
// virtual display, the report reduced to one section.
std::string shrunk(std::string command) {
  command = std::regex_replace(command, std::regex(R"(--size [0-9]+x[0-9]+)"), "--size 64x36");
  command = std::regex_replace(command, std::regex(R"(--width [0-9]+)"), "--width 64");
  command = std::regex_replace(command, std::regex(R"(--height [0-9]+)"), "--height 36");
  const bool bench = command.starts_with("build/vkray bench"), view = command.starts_with("build/vkray view");
  if (bench && command.find("--compare") == std::string::npos) {
    command = std::regex_replace(command, std::regex(R"(--frames [0-9]+)"), "--frames 1");
    if (command.find("--frames") == std::string::npos) command += " --frames 1";
    if (command.find("--size") == std::string::npos) command += " --size 64x36";
    // One round over the variants, not two: the accuracy suite's 7680x4320 case keeps its size.
    if (command.find("--rounds") == std::string::npos) command += " --rounds 1";
    // The rays suite's million rays a kind are the figures' business, not this test's.
    if (command.find("--suite rays") != std::string::npos && command.find("--rays") == std::string::npos) {
      command += " --rays 4096";
    }
    // Nor the instances suite's thousand instances, whose flattened scene holds 46M triangles.
    if (command.find("--suite instances") != std::string::npos && command.find("--instances") == std::string::npos) {
      command += " --instances 10";
    }
  }
  // The report at its reduced sizes, one section: the others are what the suite's own tests run.
  if (command.starts_with("build/vkray report")) command += " --reduced --only views";
  if (view) {
    if (command.find("--size") == std::string::npos) command += " --size 64x36";
    if (command.find("--frames") == std::string::npos) command += " --frames 2";
    command = "xvfb-run -a " + command;
  }
  return command;
}

class ReadmeExamplesTest : public vkray::test::TempDirTest {};

TEST_F(ReadmeExamplesTest, EveryVkrayCommandRuns) {
  if (!fs::is_directory(VKRAY_MODELS_DIR)) GTEST_SKIP() << "no models folder at " << VKRAY_MODELS_DIR << " (the README's examples use it)";
  if (std::system("command -v xvfb-run >/dev/null 2>&1") != 0) GTEST_SKIP() << "xvfb-run is missing (Debian: xvfb, xauth)";
  const std::vector<fs::path> pages = documents();
  ASSERT_GT(pages.size(), 1u) << "no pages in " << repository / "docs";

  // The layout the README's commands assume, from the repository root.
  const fs::path repo = dir_ / "repo";
  fs::create_directories(repo / "build");
  fs::create_directories(repo / "docs");
  // The bench's scene files, which name the models as ../../../shared/models from there.
  fs::copy(repository / "docs" / "bench-scenes", repo / "docs" / "bench-scenes");
  fs::create_directories(repo / "models");
  fs::create_directories(dir_ / "shared");
  fs::create_symlink(VKRAY_BINARY, repo / "build" / "vkray");
  fs::create_directory_symlink(fs::absolute(VKRAY_MODELS_DIR), dir_ / "shared" / "models");
  fs::create_symlink(fs::absolute(VKRAY_MODELS_DIR) / "stanford-bunny.obj", repo / "models" / "bunny.obj");
  const std::string scene = scene_example(read_text(repository / "docs" / "scene-format.md"));
  ASSERT_FALSE(scene.empty()) << "no ```json scene example in docs/scene-format.md";
  std::ofstream(repo / "scene.json") << scene;

  // Each page's commands with the page they are on; a command shown twice (a headline figure's in the
  // README, and again on its page) runs once, where it is met first.
  std::vector<std::pair<std::string, std::string>> commands;
  std::set<std::string> seen;
  for (const fs::path& page : pages) {
    const std::string text = read_text(page);
    ASSERT_FALSE(text.empty()) << page;
    const std::string name = fs::relative(page, repository).string();
    for (const std::string& line : shell_lines(text)) {
      if (!line.starts_with("build/vkray ")) {
        std::printf("not run here (CI runs the setup and test commands; the rest are a person's): %s: %s\n", name.c_str(), line.c_str());
      } else if (!seen.insert(line).second) {
        std::printf("run above already: %s: %s\n", name.c_str(), line.c_str());
      } else {
        commands.emplace_back(name, line);
      }
    }
  }

  size_t ran = 0;
  for (const auto& [page, line] : commands) {
    const std::string command = shrunk(line);
    SCOPED_TRACE(command);
    const fs::path log = dir_ / "log.txt";
    const std::string shell = "cd '" + repo.string() + "' && timeout 600 " + command + " >'" + log.string() + "' 2>&1 </dev/null";
    const auto started = std::chrono::steady_clock::now();
    const int status = std::system(shell.c_str());
    // Each command's time in the log: what to shrink first when the suite grows slow.
    std::printf("%.1f s: %s\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(), command.c_str());
    EXPECT_TRUE(status != -1 && WIFEXITED(status) && WEXITSTATUS(status) == 0)
        << page << ": command failed: " << line << "\nran as: " << command << "\n" << read_text(log);
    ++ran;
  }
  EXPECT_GE(ran, 8u) << "the sh blocks of the README and docs/ hold fewer vkray commands than expected";
}

}  // namespace
