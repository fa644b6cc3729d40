// The fuzz build's own copies of the third-party parsers (tinyobjloader, tinygltf, and the stb
// decoders tinygltf calls), compiled with the fuzzer's coverage and the sanitizers like the rest of
// the build. The packaged shared libraries are not instrumented: with them the fuzzer would see no
// coverage inside the parsers and ASan no out-of-bounds access there. Linked into vkray_core only
// when VKRAY_FUZZ is on; the archive member resolves the symbols before the shared libraries do.
#define TINYOBJLOADER_IMPLEMENTATION
#include <tiny_obj_loader.h>

// tinygltf includes <stb_image.h>; Debian installs it as <stb/stb_image.h>. Both decoders are
// static here so they cannot clash with image_io.cpp's copy.
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#include <stb/stb_image.h>
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#include <stb/stb_image_write.h>

#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_INCLUDE_STB_IMAGE
#define TINYGLTF_NO_INCLUDE_STB_IMAGE_WRITE
#include <tiny_gltf.h>
