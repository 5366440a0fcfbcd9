// PNG and JPEG decoding (io/codecs.h) with hovs' size check; a decode that passes yields the declared samples.
#include "io/codecs.h"
#include "tests/fuzz/fuzz_common.h"

namespace {

// As io's own check, with a smaller limit so that each input decodes quickly.
void SmallImage(const std::string& where, int width, int height, int channels, int bits) {
  HOVS_REQUIRE(width >= 1 && height >= 1 && int64_t(width) * height <= 4096 * 4096 && channels >= 1 && channels <= 4 &&
                   (bits == 8 || bits == 16),
               where, "refused size");
}

void Run(const std::string& input) {
  using namespace hovs::io::internal;
  Decoded d;
  if (IsPng(input))
    d = DecodePng(input, "fuzz.png", true, SmallImage);
  else if (IsJpeg(input))
    d = DecodeJpeg(input, "fuzz.jpg", true, SmallImage);
  else
    return;
  if (d.samples.size() != size_t(d.width) * d.height * d.channels * (d.bits / 8)) __builtin_trap();
}

}  // namespace

HOVS_FUZZ_TARGET(Run)
