// The film: how samples become pixels. A pixel's colour is the weighted sum of its samples in sample order; its
// ground truth comes from its centre's ray (the channels of GroundTruth, render.h), stored past the caches.
#pragma once

#if defined(__SSE__)
#include <immintrin.h>
#endif

#include "raytrace/render.h"

namespace hovs::raytrace {

// The colours of a run of neighbouring pixels (len floats: 3 per pixel) from a chunk's samples (samples rows of
// `row` floats, the run's first colour at rgb), each weighted and summed in sample order (w r0 + w r1 + ...),
// into out, or added to it (add: a pixel split over chunks adds to what its earlier chunks left).
void SumSamples(int len, int samples, int row, float weight, const float* rgb, bool add, float* out);

// The ground-truth channels (GroundTruth's order) of m pixel-centre rays, channel c of ray k at
// out[c * RayBatch::kMax + k], from the ray set-up (valid, from_mirror, mirror point M), the hits and the
// viewpoint c: range, point and normal where the ray hit something (else infinity and zeros), object id (0: sky),
// mirror mask (the ray left a mirror and did not meet the camera's own body) and the mirror point (where it left
// a mirror). The range is (p - c).norm() as Eigen sums it, ((x^2 + y^2) + z^2), then the square root. Vectorised.
void GroundTruthLanes(int m, const unsigned char* valid, const int* from_mirror, const unsigned char* hit,
                      const int* object_id, const double* c, const double* px, const double* py, const double* pz,
                      const double* nx, const double* ny, const double* nz, const double* Mx, const double* My,
                      const double* Mz, float* out);

// Pixel k's 12 ground-truth channels (c at t[c * RayBatch::kMax]) into the frame at v (16-byte aligned: frames
// are, and a pixel is 48 bytes). Streamed past the caches where the CPU can (the frame's 290 MB of ground truth
// is not read again while rendering; a row of a tile fills whole cache lines), plain stores elsewhere.
inline void StoreGroundTruthPixel(const float* t, float* v) {
  constexpr int K = RayBatch::kMax;
#if defined(__SSE__)
  _mm_stream_ps(v, _mm_setr_ps(t[0], t[K], t[2 * K], t[3 * K]));
  _mm_stream_ps(v + 4, _mm_setr_ps(t[4 * K], t[5 * K], t[6 * K], t[7 * K]));
  _mm_stream_ps(v + 8, _mm_setr_ps(t[8 * K], t[9 * K], t[10 * K], t[11 * K]));
#else
  for (int c = 0; c < GroundTruth::kChannels; ++c) v[c] = t[c * K];
#endif
}

}  // namespace hovs::raytrace
