#version 460
// View raster (docs/view.md): the interpolated (perspective-correct) per-vertex shading,
// alpha 1 where the field covers the pixel (the clear value, alpha 0, elsewhere).
layout(location = 0) in vec3 hfgi_colour;
layout(location = 0) out vec4 hfgi_out;

void main() {
    hfgi_out = vec4(hfgi_colour, 1.0);
}
