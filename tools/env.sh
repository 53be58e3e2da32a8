# Sourced by tools/test and tools/render: pins lavapipe unless HFGI_DEVICE or VK_DRIVER_FILES
# is set, and silences loader noise.
if [ -z "${VK_DRIVER_FILES:-}" ] && [ -z "${HFGI_DEVICE:-}" ] && [ -f /usr/share/vulkan/icd.d/lvp_icd.x86_64.json ]; then
  export VK_DRIVER_FILES=/usr/share/vulkan/icd.d/lvp_icd.x86_64.json
fi
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp/hfgi-xdg-$(id -u)}"
mkdir -p "$XDG_RUNTIME_DIR" && chmod 700 "$XDG_RUNTIME_DIR"
