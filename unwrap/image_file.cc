#include "io/image_io.h"
#include "unwrap/remap.h"

namespace hovs::unwrap {

Image8 LoadImage8(const std::filesystem::path& path) {
  io::Image8Bits in = io::ReadImage8(path);
  Image8 im;
  im.width = in.width, im.height = in.height, im.channels = in.channels;
  im.data = std::move(in.data);
  return im;
}

}  // namespace hovs::unwrap
