// README.md's "Groom your own mesh", run as a user runs it: the ```sh blocks between
// <!-- groom-test:begin --> and <!-- groom-test:end --> are taken from the README and run in
// order by bash, in a fresh folder laid out as the repository root is (build/spotshell and
// examples/), so the README and this test cannot drift. The block after <!-- groom-window --> is
// the interactive editor: it is left out of that run, and the window test runs it under
// xvfb-run with --frames and screenshots appended.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "noise/image.h"
#include "splat/image_compare.h"

namespace {

namespace fs = std::filesystem;

const fs::path kSource = SPOT_SOURCE_DIR;
const fs::path kTmp = fs::path(SPOT_TEST_TMP_DIR) / "readme_groom";

struct ReadmeCommands {
    std::vector<std::string> blocks; ///< the sh blocks in order, the window's left out
    std::size_t blocksBeforeWindow = 0;
    std::string windowCommand; ///< the window block's command, one line
};

std::string readFile(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

ReadmeCommands readmeCommands() {
    const std::string readme = readFile(kSource / "README.md");
    const std::string beginMark = "<!-- groom-test:begin -->";
    const std::string endMark = "<!-- groom-test:end -->";
    const std::size_t begin = readme.find(beginMark);
    const std::size_t end = readme.find(endMark);
    ReadmeCommands r;
    if (begin == std::string::npos || end == std::string::npos || end < begin) {
        ADD_FAILURE() << "README.md lacks the " << beginMark << " ... " << endMark << " markers";
        return r;
    }
    const std::string section = readme.substr(begin, end - begin);
    const std::string fence = "```sh\n";
    std::size_t at = 0;
    while ((at = section.find(fence, at)) != std::string::npos) {
        const std::size_t close = section.find("\n```", at + fence.size());
        if (close == std::string::npos) {
            ADD_FAILURE() << "an unclosed ```sh block in README.md's groom section";
            break;
        }
        const std::string block = section.substr(at + fence.size(), close + 1 - at - fence.size());
        const std::string before = section.substr(0, at);
        const std::size_t lastLine = before.rfind('\n', before.size() >= 2 ? before.size() - 2 : 0);
        const bool window = before.substr(lastLine == std::string::npos ? 0 : lastLine + 1)
                                .find("<!-- groom-window -->") != std::string::npos;
        if (window) {
            r.windowCommand = block.substr(0, block.find('\n'));
            r.blocksBeforeWindow = r.blocks.size();
        } else {
            r.blocks.push_back(block);
        }
        at = close + 4;
    }
    return r;
}

/// A fresh folder with build/spotshell and examples/ as in the repository root.
fs::path workFolder(const std::string& name) {
    const fs::path dir = kTmp / name;
    fs::remove_all(dir);
    fs::create_directories(dir / "build");
    fs::create_symlink(SPOT_SPOTSHELL, dir / "build" / "spotshell");
    fs::create_directory_symlink(kSource / "examples", dir / "examples");
    return dir;
}

/// Runs `script` with bash -e in `dir`; the exit code, and everything it printed in `log`.
int runBash(const fs::path& dir, const std::string& script, std::string& log) {
    const fs::path file = dir / "commands.sh";
    std::ofstream(file) << "set -euo pipefail\n" << script;
    const fs::path logFile = dir / "commands.log";
    const std::string cmd =
        "cd '" + dir.string() + "' && bash -x commands.sh >'" + logFile.string() + "' 2>&1";
    const int status = std::system(cmd.c_str());
    log = readFile(logFile);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// Fraction of pixels more than 0.05 away from `background` (linear) in some channel: the fur.
double covered(const spot::noise::Image& image, glm::vec3 background) {
    std::size_t n = 0;
    for (const glm::vec3& p : image.pixels)
        n += glm::any(glm::greaterThan(glm::abs(p - background), glm::vec3(0.05f)));
    return double(n) / double(image.pixels.size());
}

// The scene's background (README step 4).
const glm::vec3 kBackground(0.6f, 0.7f, 0.8f);

TEST(ReadmeGroom, CommandsRunAsWritten) {
    const ReadmeCommands readme = readmeCommands();
    ASSERT_GE(readme.blocks.size(), 5u);
    std::string all;
    for (const std::string& block : readme.blocks)
        all += block;
    const fs::path dir = workFolder("commands");
    std::string log;
    ASSERT_EQ(runBash(dir, all, log), 0) << log;

    using spot::noise::readImage;
    const fs::path out = dir / "my-groom";
    const spot::noise::Image first = readImage(out / "first.png");
    const spot::noise::Image edited = readImage(out / "edited.png");
    const spot::noise::Image groomed = readImage(out / "groomed.png");
    const spot::noise::Image baked = readImage(out / "baked.png");
    // The furry pebble fills about a third of the frame in every image.
    for (const auto* image : {&first, &edited, &groomed, &baked}) {
        EXPECT_EQ(image->width, 480);
        EXPECT_EQ(image->height, 360);
        const double c = covered(*image, kBackground);
        EXPECT_GT(c, 0.25) << "fur covers " << c << " of the image";
        EXPECT_LT(c, 0.6) << "fur covers " << c << " of the image";
    }
    // The saved preset renders what the editor showed; the bake renders what the kernels do;
    // the strokes changed the groom.
    const double savedDb = spot::splat::psnr(edited, groomed);
    const double bakeDb = spot::splat::psnr(groomed, baked);
    const double editDb = spot::splat::psnr(first, edited);
    EXPECT_GT(savedDb, 40.0) << "the editor's screenshot against the saved preset's render";
    EXPECT_GT(bakeDb, 30.0) << "the bake against the kernels";
    EXPECT_LT(editDb, 30.0) << "the painted groom against the first one";
    std::printf("README groom: %s; saved preset %.1f dB, bake %.1f dB, edit %.1f dB\n",
                out.string().c_str(), savedDb, bakeDb, editDb);
}

TEST(ReadmeGroomWindow, TheEditorOpensOnTheScene) {
    const ReadmeCommands readme = readmeCommands();
    ASSERT_FALSE(readme.windowCommand.empty()) << "no block after <!-- groom-window -->";
    ASSERT_EQ(readme.windowCommand.find("--script"), std::string::npos) << readme.windowCommand;
    std::string before;
    for (std::size_t i = 0; i < readme.blocksBeforeWindow; ++i)
        before += readme.blocks[i];
    const fs::path dir = workFolder("window");
    std::string log;
    ASSERT_EQ(runBash(dir,
                      before + "SPOT_VALIDATION=1 xvfb-run -a -s '-screen 0 1280x1024x24' " +
                          readme.windowCommand +
                          " --frames 3 --screenshot my-groom/window-scene.png"
                          " --window-screenshot my-groom/window.png\n",
                      log),
              0)
        << log;
    const spot::noise::Image scene = spot::noise::readImage(dir / "my-groom" / "window-scene.png");
    const double c = covered(scene, kBackground);
    EXPECT_GT(c, 0.1) << "fur covers " << c << " of the editor's view";
    EXPECT_TRUE(fs::is_regular_file(dir / "my-groom" / "window.png"));
    std::printf("README groom window: %s\n", (dir / "my-groom").string().c_str());
}

} // namespace
