// Start-up (splat/pipeline_cache_vk.h): pipelines made on worker threads give the same images as
// pipelines made one by one; a frame makes only the pipelines it draws with; the pipeline cache
// file written by one context is read by the next, and a corrupt or foreign one is ignored with
// one warning line. Counters, never timings: the speed is measured in docs/design.md, "Start-up".
#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#include <gtest/gtest.h>

#include "splat/frame_vk.h"
#include "splat_test_support.h"

namespace {

using namespace spot;
using namespace spot::test;
namespace fs = std::filesystem;

/// A fresh folder for one test's cache.
fs::path cacheFolder(const std::string& name) {
    const fs::path dir =
        fs::path(SPOT_TEST_TMP_DIR) / ("pipeline-cache-" + name + "-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

splat::ContextOptions options(const fs::path& cache, int threads) {
    splat::ContextOptions o = validated();
    o.pipelineCache = cache.string();
    o.pipelineThreads = threads;
    return o;
}

struct Rendered {
    noise::Image image;
    splat::PipelineStats stats;
    splat::PipelineCacheInfo cache;
};

/// One frame of `method` in a context of its own (its cache written when it goes away).
Rendered renderOnce(const FrameSetup& s, const splat::ContextOptions& o,
                    const std::string& method = "sorted") {
    Rendered r;
    splat::Context ctx(o);
    r.cache = ctx.pipelineCacheInfo();
    splat::Frame frame(ctx, s.mesh, *s.generator);
    frame.render(method, s.view(), splat::RenderSettings{}, &r.image);
    r.stats = ctx.pipelineStats();
    expectNoValidationErrors(ctx);
    return r;
}

bool sameBytes(const noise::Image& a, const noise::Image& b) {
    return a.width == b.width && a.height == b.height && a.pixels.size() == b.pixels.size() &&
           std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(glm::vec3)) ==
               0 &&
           a.alpha == b.alpha;
}

fs::path theFile(const fs::path& dir) {
    for (const fs::directory_entry& e : fs::directory_iterator(dir))
        if (e.path().extension() == ".bin")
            return e.path();
    return {};
}

TEST(PipelineCache, ASecondContextMakesItsPipelinesFromTheFirstOnesFile) {
    const FrameSetup s = loadFrameSetup("fur-bunny", 48);
    const fs::path dir = cacheFolder("second");
    const Rendered first = renderOnce(s, options(dir, 2));
    EXPECT_FALSE(first.cache.loaded); // nothing there yet
    EXPECT_TRUE(first.cache.ignored.empty()) << first.cache.ignored;
    EXPECT_GT(first.stats.created, 0u);
    EXPECT_EQ(first.stats.fromCache, 0u);
    const fs::path file = theFile(dir);
    ASSERT_FALSE(file.empty()) << "no cache file written in " << dir;
    EXPECT_EQ(file.parent_path(), dir);

    const Rendered second = renderOnce(s, options(dir, 2));
    EXPECT_TRUE(second.cache.loaded);
    EXPECT_EQ(second.cache.path, file.string());
    EXPECT_EQ(second.cache.keys, first.stats.created);
    EXPECT_EQ(second.stats.created, first.stats.created);
    EXPECT_EQ(second.stats.fromCache, second.stats.created) << "pipelines not found in the cache";
    EXPECT_TRUE(sameBytes(first.image, second.image));
    fs::remove_all(dir);
}

TEST(PipelineCache, ImagesAreBitIdenticalSerialParallelAndFromTheCache) {
    const FrameSetup s = loadFrameSetup("fur-bunny", 48);
    const fs::path dir = cacheFolder("identical");
    // Made one by one when drawn, no cache: the start-up before the pipeline threads.
    const Rendered serial = renderOnce(s, options({}, 0));
    EXPECT_TRUE(serial.cache.path.empty());
    const Rendered parallel = renderOnce(s, options(dir, 2)); // writes the cache
    const Rendered cached = renderOnce(s, options(dir, 2));   // reads it
    EXPECT_GT(cached.stats.fromCache, 0u);
    EXPECT_TRUE(sameBytes(serial.image, parallel.image));
    EXPECT_TRUE(sameBytes(serial.image, cached.image));
    // An unlit method too (other pipelines: the unlit mesh pass, oit's passes).
    FrameSetup unlit = loadFrameSetup("fur-bunny", 48);
    unlit.scene.shading.mode = noise::Shading::Mode::Unlit;
    EXPECT_TRUE(sameBytes(renderOnce(unlit, options({}, 0), "oit").image,
                          renderOnce(unlit, options(dir, 2), "oit").image));
    fs::remove_all(dir);
}

TEST(PipelineCache, AFrameMakesOnlyThePipelinesItDraws) {
    const FrameSetup lit = loadFrameSetup("fur-bunny", 48);
    for (const char* method : {"sorted", "oit"}) {
        const Rendered r = renderOnce(lit, options({}, 2), method);
        EXPECT_GT(r.stats.created, 0u) << method;
        EXPECT_EQ(r.stats.used, r.stats.created) << method << ": pipelines made but not drawn";
    }
    FrameSetup unlit = loadFrameSetup("fur-bunny", 48);
    unlit.scene.shading.mode = noise::Shading::Mode::Unlit;
    const Rendered r = renderOnce(unlit, options({}, 2), "sorted");
    EXPECT_EQ(r.stats.used, r.stats.created) << "unlit: pipelines made but not drawn";
}

/// Write `bytes` as the cache file `file` names and start a context with it: the file is
/// ignored with one warning line naming it and why, and rewritten whole when the context goes
/// away (the next one reads it). With `expected`, a frame is rendered too, as without a cache.
void expectIgnored(const FrameSetup& s, const fs::path& dir, const fs::path& file,
                   const std::string& bytes, const std::string& why,
                   const noise::Image* expected = nullptr) {
    {
        std::ofstream out(file, std::ios::binary | std::ios::trunc);
        out.write(bytes.data(), std::streamsize(bytes.size()));
    }
    testing::internal::CaptureStderr();
    splat::PipelineCacheInfo info;
    if (expected) {
        const Rendered r = renderOnce(s, options(dir, 2));
        info = r.cache;
        EXPECT_EQ(r.stats.fromCache, 0u) << why;
        EXPECT_TRUE(sameBytes(r.image, *expected)) << why;
    } else {
        info = splat::Context(options(dir, 2)).pipelineCacheInfo();
    }
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_FALSE(info.loaded) << why;
    EXPECT_NE(info.ignored.find(why), std::string::npos) << info.ignored;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_NE(err.find("warning: pipeline cache " + file.string() + " ignored: " + why),
              std::string::npos)
        << err;
    EXPECT_TRUE(splat::Context(options(dir, 2)).pipelineCacheInfo().loaded) << why;
}

TEST(PipelineCache, ACorruptOrForeignFileIsIgnoredWithOneWarning) {
    FrameSetup s = loadFrameSetup("fur-bunny", 32);
    s.scene.shading.mode = noise::Shading::Mode::Unlit; // fewer pipelines: a quicker test
    const fs::path dir = cacheFolder("corrupt");
    const Rendered made = renderOnce(s, options(dir, 2));
    const fs::path file = theFile(dir);
    ASSERT_FALSE(file.empty());
    std::string good;
    {
        std::ifstream in(file, std::ios::binary);
        good.assign(std::istreambuf_iterator<char>(in), {});
    }
    ASSERT_GT(good.size(), 64u);
    expectIgnored(s, dir, file, "garbage", "shorter than its header", &made.image);
    expectIgnored(s, dir, file, std::string(200, 'x'), "not a spotshell pipeline cache");
    std::string flipped = good;
    flipped.back() ^= 0x5a; // the driver's data
    expectIgnored(s, dir, file, flipped, "corrupt");
    expectIgnored(s, dir, file, good.substr(0, good.size() - 3), "truncated");
    std::string foreign = good;
    foreign[24] ^= 0x01; // pipelineCacheUUID's first byte (after magic, format and 3 ids)
    expectIgnored(s, dir, file, foreign, "made by another driver");
    std::string format = good;
    format[8] = char(0x7f); // a format version this build does not write
    expectIgnored(s, dir, file, format, "format 127");
    fs::remove_all(dir);
}

TEST(PipelineCache, AFolderThatCannotBeWrittenIsAWarningNotAnError) {
    FrameSetup s = loadFrameSetup("fur-bunny", 32);
    s.scene.shading.mode = noise::Shading::Mode::Unlit;
    const fs::path dir = cacheFolder("unwritable");
    const fs::path blocked = dir / "a-file-not-a-folder";
    { std::ofstream(blocked) << "x"; }
    testing::internal::CaptureStderr();
    const Rendered r = renderOnce(s, options(blocked, 2));
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_GT(r.stats.created, 0u);
    EXPECT_NE(err.find("not written"), std::string::npos) << err;
    fs::remove_all(dir);
}

} // namespace
