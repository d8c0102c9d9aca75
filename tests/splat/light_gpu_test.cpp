// The lit shading model on the GPU: shaders/light_check.comp runs spot_light.h's functions on
// the device and its numbers are the float twin's (tests/shaders/light_test.cpp checks those
// against their closed forms).
#include <cmath>
#include <cstring>

#include <gtest/gtest.h>

#include "shaders/spot_light.hpp"
#include "splat/context_vk.h"
#include "splat/pass_vk.h"
#include "splat_test_support.h"

#include "light_check.comp.h"

namespace {

using namespace spot;
namespace f32 = spot::shared::f32;

TEST(LightModelGpu, TheDeviceComputesTheFloatTwinsNumbers) {
    splat::Context ctx(test::validated());
    constexpr int kValues = 7;
    splat::Buffer out(ctx, kValues * sizeof(float), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                      splat::Buffer::Memory::HostVisible, "light check");
    std::memset(out.mapped(), 0xff, kValues * sizeof(float)); // NaN until written
    const splat::Pipeline pipeline = splat::makeComputePipeline(
        ctx, splat::spirv(spv_light_check_comp), {splat::storageBuffer(0)}, 0);
    ctx.submitAndWait([&](VkCommandBuffer cmd) {
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.handle());
        splat::Descriptors().buffer(0, out).push(ctx, cmd, pipeline);
        vkCmdDispatch(cmd, 1, 1, 1);
    });
    float gpu[kValues];
    std::memcpy(gpu, out.mapped(), sizeof gpu);

    // light_check.comp's main(), on the CPU.
    const glm::vec3 t = glm::normalize(glm::vec3(1, 0, 0)), l = glm::normalize(glm::vec3(1, 1, 0)),
                    v = glm::normalize(glm::vec3(0, 1, 1)), c(0.5f, 0.25f, 0.125f);
    const glm::vec3 primary(glm::radians(-6.0f), glm::radians(8.0f), 0.3f);
    const glm::vec3 secondary(glm::radians(9.0f), glm::radians(16.0f), 0.5f);
    const glm::vec3 s = f32::spotLobeShade(f32::kSpotShadeStrand, t, l, v, c, primary, secondary);
    const glm::vec3 f =
        f32::spotLobeShade(f32::kSpotShadeFlake, glm::vec3(0, 0, -1), l, v, c, primary, secondary);
    const glm::vec3 n =
        f32::spotLobeShade(f32::kSpotShadeLambert, glm::vec3(0, 1, 0), l, v, c, primary, secondary);
    const glm::vec3 axis = f32::spotPlacedAxis(glm::vec3(0, 0, 1), glm::vec3(0, 0, 1),
                                               glm::mat3(1.0f), glm::vec3(1.0f), 0.5f);
    const glm::vec3 normal = f32::spotPlacedNormal(glm::mat3(2.0f), 2);
    const glm::vec3 sky = f32::spotSkyDirection(0.5f, 0.25f);
    const float cpu[kValues] = {s.x,
                                s.y,
                                f.x,
                                n.x,
                                axis.x,
                                normal.z,
                                sky.y + f32::spotPointFalloff(4.0f, 2.0f) +
                                    f32::spotLobeDiffuse(f32::kSpotShadeFlake, t, l, v)};
    // The hand-worked values (light_test.cpp): the strand's red, Lambert's n.l = 1/sqrt2 x 0.5,
    // the bent axis sin 0.5, the flake seen edge-on from v (n.l = 0 after turning).
    EXPECT_NEAR(cpu[0], 0.4777581f, 1e-6f);
    EXPECT_NEAR(cpu[3], 0.5f * std::sqrt(0.5f), 1e-6f);
    EXPECT_NEAR(cpu[4], std::sin(0.5f), 1e-6f);
    EXPECT_NEAR(cpu[5], 1.0f, 1e-6f);
    for (int i = 0; i < kValues; ++i) {
        // exp, sqrt, sin and normalize are not correctly rounded on either side: a few ulps.
        EXPECT_NEAR(gpu[i], cpu[i], 2e-6f * std::max(1.0f, std::abs(cpu[i]))) << "value " << i;
    }
    test::expectNoValidationErrors(ctx);
}

} // namespace
