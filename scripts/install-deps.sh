#!/usr/bin/env bash
# Install the Debian 12 packages spotshell needs. Idempotent: installs only what is missing, and
# does nothing (not even apt-get update) when everything is present. Needs root for installing.
set -euo pipefail

packages=(
  # toolchain
  cmake ninja-build clang libclang-rt-14-dev g++ pkg-config
  # libraries
  libglm-dev libopenvdb-dev libboost-dev libboost-iostreams-dev libtbb-dev
  libopenimageio-dev nlohmann-json3-dev libtinyobjloader-dev
  # glTF 2.0 (animated meshes: noise/animated_mesh.h)
  libtinygltf-dev
  # oiiotool: the alpha test composites a render over a plate as users do
  openimageio-tools
  # Vulkan on the CPU (lavapipe) with validation, shaders
  # (vulkan-validationlayers-dev: vk_enum_string_helper.h, the names of VkResult values)
  libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers vulkan-validationlayers-dev
  glslang-tools
  # tests; vdb_print (libopenvdb-tools) reads the bake's files as users' tools do
  libgtest-dev libgmock-dev libbenchmark-dev libopenvdb-tools
  # the editor's window: GLFW, Dear ImGui (core and backend sources), a virtual display for tests
  libglfw3-dev libimgui-dev xvfb xauth
  # X events for the window test that drives the real window (tests/editor/window_test.cpp)
  xdotool
  # the farm test: a one-node Slurm on loopback (tests/farm/), and the shot's MP4
  slurm-wlm munge ffmpeg
  # the benchmark's charts
  python3 python3-matplotlib
  # real clients of the exports (tests/interop, scripts/blender): Node.js for the npm packages
  # (3DGS converter and web viewer, Node >= 18), headless Chromium for the viewer (software WebGL),
  # Blender (3.4) for the impulses importer's test
  nodejs chromium blender
)
# npm: Debian's package, unless the installed Node.js bundles its own (nodesource's does)
command -v npm >/dev/null 2>&1 || packages+=(npm)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${#missing[@]} packages: ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then
    SUDO=sudo
  else
    echo "install-deps: error: need root to install: ${missing[*]}" >&2
    exit 1
  fi
else
  SUDO=
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
echo "install-deps: done"
