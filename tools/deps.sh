#!/usr/bin/env bash
# Installs the Debian packages hfgi needs (Vulkan loader, lavapipe, validation layers and the
# static shaderc/glslang/SPIRV-Tools libraries, and the DejaVu font that `hfgi bench` plots use),
# only those missing. Needs root or sudo.
set -euo pipefail
pkgs=(libvulkan1 mesa-vulkan-drivers vulkan-validationlayers libshaderc-dev glslang-dev spirv-tools fonts-dejavu-core)
if [ "${HFGI_SHADERC_FROM_SOURCE:-0}" = 1 ]; then pkgs+=(cmake ninja-build python3 g++); fi
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
echo "installing: ${missing[*]}" >&2
sudo=""
[ "$(id -u)" = 0 ] || sudo="sudo"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
