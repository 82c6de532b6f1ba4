// Every vkray command the README and the manual's pages (docs/*.md) show in a ```sh block runs and
// exits 0, each distinct command a test of its own (the README's first, then the pages' by file
// name), in a temporary copy of the layout they assume (build/vkray, ../shared/models, docs/ with its
// bench scenes, a scene.json made of docs/scene-format.md's own scene example). So an option renamed,
// removed or misspelt in the README or a page fails here. To keep the suite short, image sizes are cut to 64x36, the bench to one
// frame of one round, the rays suite to 4096 rays a kind and point counts to a few thousand: what this checks is that each
// command is accepted and works, not the figures beside it (those come from the commands as
// printed, re-run by hand). `view` commands run under xvfb-run for
// two frames. The setup and test commands (install-deps, cmake, ctest) are what CI itself runs.
#include "tests/temp_dir_test.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cctype>
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
    // The accuracy suite's 7680x4320 case keeps its size: with each variant it ran 154 s, with the
    // first (the default) 31 s. That the others are variants is --variants' business, checked by
    // the CLI's own tests.
    if (command.find("--suite accuracy") != std::string::npos) {
      command = std::regex_replace(command, std::regex(R"(--variants ([^, ]+)\S*)"), "--variants $1");
    }
    // Nor the instances suite's thousand instances, whose flattened scene holds 46M triangles.
    if (command.find("--suite instances") != std::string::npos && command.find("--instances") == std::string::npos) {
      command += " --instances 10";
    }
    // Nor the points suite's million points a set (its signed distances take minutes here).
    if (command.find("--suite points") != std::string::npos) {
      command = std::regex_replace(command, std::regex(R"(--points [0-9]+)"), "--points 4096");
      if (command.find("--points") == std::string::npos) command += " --points 4096";
    }
  }
  // The points command's grid and samples, as small: what it writes is its own tests' business.
  if (command.starts_with("build/vkray points")) {
    command = std::regex_replace(command, std::regex(R"(--grid [0-9]+)"), "--grid 8");
    command = std::regex_replace(command, std::regex(R"(--(uniform|near-surface) [0-9]+)"), "--$1 1000");
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

// A command of a page, as the test runs it (shrunk), and the earlier commands whose files it reads
// (bench --compare A B: those that wrote A and B with --json), run first in its folder.
struct PageCommand {
  std::string page;  // README.md or docs/NAME.md
  std::string line;  // as the page shows it
  std::vector<std::string> before;  // earlier lines, as their pages show them
  std::string name;  // the test's: the page and the command's place in it
};

// Every distinct vkray command of the pages, in order: a command shown twice (a headline figure's
// in the README, and again on its page) is tested where it is met first; the others are printed at
// discovery as what this does not run (CI runs the setup and test commands; the rest are a person's).
std::vector<PageCommand> page_commands() {
  std::vector<PageCommand> commands;
  std::set<std::string> seen;
  for (const fs::path& page : documents()) {
    const std::string name = fs::relative(page, repository).string();
    size_t place = 0;
    for (const std::string& line : shell_lines(read_text(page))) {
      if (!line.starts_with("build/vkray ") || !seen.insert(line).second) continue;
      PageCommand command{name, line, {}, name + "_" + std::to_string(++place)};
      for (char& c : command.name) {
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      }
      std::smatch compared;
      if (std::regex_search(line, compared, std::regex(R"(--compare (\S+) (\S+))"))) {
        for (const std::string& file : {compared[1].str(), compared[2].str()}) {
          for (const PageCommand& earlier : commands) {
            if (earlier.line.find("--json " + file) != std::string::npos) command.before.push_back(earlier.line);
          }
        }
      }
      commands.push_back(std::move(command));
    }
  }
  return commands;
}

const std::vector<PageCommand>& every_command() {
  static const std::vector<PageCommand> all = page_commands();
  return all;
}

class ReadmeCommand : public vkray::test::TempDirTest, public testing::WithParamInterface<size_t> {};

// Each command a test of its own (ctest runs them side by side, each within the suite's budget), in a
// folder laid out as the pages assume, from the repository root.
TEST_P(ReadmeCommand, Runs) {
  if (!fs::is_directory(VKRAY_MODELS_DIR)) GTEST_SKIP() << "no models folder at " << VKRAY_MODELS_DIR << " (the pages' examples use it)";
  if (std::system("command -v xvfb-run >/dev/null 2>&1") != 0) GTEST_SKIP() << "xvfb-run is missing (Debian: xvfb, xauth)";
  const PageCommand& page_command = every_command()[GetParam()];
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

  std::vector<std::string> lines = page_command.before;
  lines.push_back(page_command.line);
  for (const std::string& line : lines) {
    const std::string command = shrunk(line);
    SCOPED_TRACE(command);
    const fs::path log = dir_ / "log.txt";
    const std::string shell = "cd '" + repo.string() + "' && timeout 600 " + command + " >'" + log.string() + "' 2>&1 </dev/null";
    const auto started = std::chrono::steady_clock::now();
    const int status = std::system(shell.c_str());
    std::printf("%.1f s: %s\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(), command.c_str());
    ASSERT_TRUE(status != -1 && WIFEXITED(status) && WEXITSTATUS(status) == 0)
        << page_command.page << ": command failed: " << line << "\nran as: " << command << "\n" << read_text(log);
  }
}

std::string command_name(const testing::TestParamInfo<size_t>& command) { return every_command()[command.param].name; }

INSTANTIATE_TEST_SUITE_P(Pages, ReadmeCommand, testing::Range(size_t{0}, every_command().size()), command_name);

// The pages hold the commands this runs: a page whose sh blocks lost their commands fails here.
TEST(ReadmeCommands, ThePagesShowEnoughCommands) { EXPECT_GE(every_command().size(), 8u); }

}  // namespace
