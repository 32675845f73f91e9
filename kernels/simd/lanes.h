// The one SIMD vocabulary of kernels/: lanes of float, int32 and mask, and the verbs
// kernels use on them. A kernel is written once as a template over a lane type `F`
// (FloatN<N>) and instantiated twice: FloatW (kSimdWidth lanes) or FloatP (kPairWidth
// lanes, the one-pair-per-lane kernels), the SIMD path, and Float1 (one plain float,
// the scalar reference path).
//
//   FloatN<N>  N floats           arithmetic + - * /, unary -, compare -> MaskN<N>
//   MaskN<N>   N lane predicates  & | ^ ~, andnot, any / all / none, bits (one bit a
//              lane); bits_lt(a, b) = bits(a < b) without widening the mask (AVX-512)
//   IntN<N>    N int32            + - & >>, select, load / store, to_float, lane access
//   verbs      load / store (contiguous, unaligned), broadcast (implicit from float),
//              mul_add, min, max, abs, sqrt, select(mask, if_true, if_false),
//              copysign-free sign helpers are built from select;
//              gather(float array, index lanes): lane i of array[index_i];
//              gather_lanes(array of lanes, index lanes): lane i of array[index_i];
//              expand_store<N>(dst, src, bits): the set lanes of dst from src[0, 1, ..]
//              (the inverse of compacting a block's live lanes; float, or int32 to uint8);
//              compact_store<N>(dst, int lanes, bits): the set lanes to dst[0, 1, ..];
//              load_transposed(N row pointers): N rows of N floats, one per lane;
//              store_transposed(N row pointers, bits): its inverse, for the set lanes only;
//              gather4(records, stride, index array): 4 floats of each lane's record
//              (16-byte loads and a transpose, no gather); gather_xyz: the first three
//              of 4-float records;
//              SortedGather(index lanes, begin, end)(array): gather's values for index
//              lanes close together (a listed group), by windows and permutes;
//              load_clamped<F>(p, i, n): p[i ..] with indices past n - 1 reading p[n - 1];
//              tag / tag_index: a small index kept in a float's 5 low mantissa bits,
//              so one max/min tree gives both the extreme and where it came from.
//   box_halves_overlap (box_overlap.h): two boxes, each as two 16-byte halves (min,
//              max, lane 3 spare), overlap in one 4-lane compare per half.
//
// Width: kSimdWidth = 8 where AVX is enabled (one ymm register), 4 elsewhere (SSE2 /
// NEON / any target: GCC lowers the generic vectors itself), 1 with -DIMPACT_SIMD_SCALAR.
// Why GCC/Clang vector extensions rather than Highway or xsimd: the kernels need a
// dozen verbs on one fixed width, the extensions give exactly that with the
// compiler's own register allocation and instruction selection on every target, and
// add no dependency; intrinsics appear only where the extensions have no spelling
// (sqrt, min/max, movemask) and each has a portable fallback.
//
// Semantics: every verb is lane-wise and IEEE (sqrt and / correctly rounded; no
// approximate rsqrt/rcp), so a lane's result never depends on its neighbours: a
// kernel gives the same bytes for a pair whichever block / range it lands in.
// min/max follow the x86 rule (second operand on NaN); kernels assume finite inputs.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

#if defined(__SSE2__) || defined(__AVX__)
#include <immintrin.h>
#endif

#include "kernels/common/kernel.h"

namespace impact::kernels::simd {

#if defined(IMPACT_SIMD_SCALAR)
inline constexpr uint32_t kSimdWidth = 1;
#elif defined(__AVX__)
inline constexpr uint32_t kSimdWidth = 8;
#else
inline constexpr uint32_t kSimdWidth = 4;
#endif

template <uint32_t N>
struct MaskN;
template <uint32_t N>
struct IntN;

/// The raw generic vector types (spelled per width: GCC drops a vector_size that
/// depends on a template parameter inside a class template).
template <uint32_t N>
struct RawVec;
template <>
struct RawVec<4> {
  typedef float F __attribute__((vector_size(16)));
  typedef int32_t I __attribute__((vector_size(16)));
  typedef uint32_t U __attribute__((vector_size(16)));
};
template <>
struct RawVec<8> {
  typedef float F __attribute__((vector_size(32)));
  typedef int32_t I __attribute__((vector_size(32)));
  typedef uint32_t U __attribute__((vector_size(32)));
};
template <>
struct RawVec<16> {
  typedef float F __attribute__((vector_size(64)));
  typedef int32_t I __attribute__((vector_size(64)));
  typedef uint32_t U __attribute__((vector_size(64)));
};

/// The operators of both float lane types (FloatN<N>, FloatN<1>), spelled once and
/// stamped into each: lane-wise arithmetic on the member v (a generic vector, or a
/// float) and comparisons giving the type's Mask. A macro, not a base class, so that the
/// operators stay each type's own members and hidden friends: the compiler sees the
/// code as if written out in each.
// clang-format off
#define IMPACT_FLOAT_LANE_OPERATORS                                                                   \
  friend IMPACT_INLINE FloatN operator+(FloatN a, FloatN b) { return FloatN(a.v + b.v); }          \
  friend IMPACT_INLINE FloatN operator-(FloatN a, FloatN b) { return FloatN(a.v - b.v); }          \
  friend IMPACT_INLINE FloatN operator*(FloatN a, FloatN b) { return FloatN(a.v * b.v); }          \
  friend IMPACT_INLINE FloatN operator/(FloatN a, FloatN b) { return FloatN(a.v / b.v); }          \
  friend IMPACT_INLINE FloatN operator-(FloatN a) { return FloatN(-a.v); }                         \
  IMPACT_INLINE FloatN& operator+=(FloatN b) { v += b.v; return *this; }                           \
  IMPACT_INLINE FloatN& operator-=(FloatN b) { v -= b.v; return *this; }                           \
  IMPACT_INLINE FloatN& operator*=(FloatN b) { v *= b.v; return *this; }                           \
  friend IMPACT_INLINE Mask operator<(FloatN a, FloatN b) { return Mask(a.v < b.v); }              \
  friend IMPACT_INLINE Mask operator<=(FloatN a, FloatN b) { return Mask(a.v <= b.v); }            \
  friend IMPACT_INLINE Mask operator>(FloatN a, FloatN b) { return Mask(a.v > b.v); }              \
  friend IMPACT_INLINE Mask operator>=(FloatN a, FloatN b) { return Mask(a.v >= b.v); }            \
  friend IMPACT_INLINE Mask operator==(FloatN a, FloatN b) { return Mask(a.v == b.v); }            \
  friend IMPACT_INLINE Mask operator!=(FloatN a, FloatN b) { return Mask(a.v != b.v); }
// clang-format on

// ---------------------------------------------------------------------------------------
// N > 1: GCC / Clang generic vectors.
// ---------------------------------------------------------------------------------------

/// N lanes of float.
template <uint32_t N>
struct FloatN {
  using Raw = typename RawVec<N>::F;
  using IRaw = typename RawVec<N>::I;
  static constexpr uint32_t kWidth = N;
  using Mask = MaskN<N>;
  using Int = IntN<N>;

  Raw v;

  FloatN() = default;
  /// Broadcast (implicit, so literals mix with lanes: 0.5f * x). Spelled s - 0, which
  /// is s exactly (-0 included) and compiles to a bare broadcast; 0 + s would cost an
  /// extra add per broadcast and turn -0 into +0.
  IMPACT_INLINE FloatN(float s) : v(s - Raw{}) {}
  IMPACT_INLINE explicit FloatN(Raw r) : v(r) {}

  /// N contiguous floats from p (no alignment needed).
  static IMPACT_INLINE FloatN load(const float* p) {
    FloatN r;
    std::memcpy(&r.v, p, sizeof(Raw));
    return r;
  }
  IMPACT_INLINE void store(float* p) const { std::memcpy(p, &v, sizeof(Raw)); }
  IMPACT_INLINE float lane(uint32_t i) const { return v[i]; }

  IMPACT_FLOAT_LANE_OPERATORS
};

/// N lane predicates: each lane all ones (true) or zero.
template <uint32_t N>
struct MaskN {
  using Raw = typename RawVec<N>::I;
  static constexpr uint32_t kWidth = N;
  Raw v;

  MaskN() = default;
  IMPACT_INLINE explicit MaskN(Raw r) : v(r) {}
  /// Every lane b.
  IMPACT_INLINE explicit MaskN(bool b) : v(Raw{} + (b ? -1 : 0)) {}
  IMPACT_INLINE bool lane(uint32_t i) const { return v[i] != 0; }

  friend IMPACT_INLINE MaskN operator&(MaskN a, MaskN b) { return MaskN(a.v & b.v); }
  friend IMPACT_INLINE MaskN operator|(MaskN a, MaskN b) { return MaskN(a.v | b.v); }
  friend IMPACT_INLINE MaskN operator^(MaskN a, MaskN b) { return MaskN(a.v ^ b.v); }
  friend IMPACT_INLINE MaskN operator~(MaskN a) { return MaskN(~a.v); }
};

/// N lanes of int32.
template <uint32_t N>
struct IntN {
  using Raw = typename RawVec<N>::I;
  static constexpr uint32_t kWidth = N;
  Raw v;

  IntN() = default;
  IMPACT_INLINE IntN(int32_t s) : v(Raw{} + s) {}
  IMPACT_INLINE explicit IntN(Raw r) : v(r) {}
  /// N contiguous int32 from p (no alignment needed).
  static IMPACT_INLINE IntN load(const int32_t* p) {
    IntN r;
    std::memcpy(&r.v, p, sizeof(Raw));
    return r;
  }
  IMPACT_INLINE void store(int32_t* p) const { std::memcpy(p, &v, sizeof(Raw)); }
  IMPACT_INLINE int32_t lane(uint32_t i) const { return v[i]; }

  friend IMPACT_INLINE IntN operator+(IntN a, IntN b) { return IntN(a.v + b.v); }
  friend IMPACT_INLINE IntN operator-(IntN a, IntN b) { return IntN(a.v - b.v); }
  friend IMPACT_INLINE IntN operator&(IntN a, IntN b) { return IntN(a.v & b.v); }
  /// Arithmetic shift right by s (0 <= s < 32).
  friend IMPACT_INLINE IntN operator>>(IntN a, int s) { return IntN(a.v >> s); }
  friend IMPACT_INLINE MaskN<N> operator==(IntN a, IntN b) { return MaskN<N>(a.v == b.v); }
  friend IMPACT_INLINE MaskN<N> operator>(IntN a, IntN b) { return MaskN<N>(a.v > b.v); }
};

template <uint32_t N>
IMPACT_INLINE FloatN<N> select(MaskN<N> m, FloatN<N> a, FloatN<N> b) {
  return FloatN<N>(m.v ? a.v : b.v);
}
template <uint32_t N>
IMPACT_INLINE IntN<N> select(MaskN<N> m, IntN<N> a, IntN<N> b) {
  return IntN<N>(m.v ? a.v : b.v);
}
template <uint32_t N>
IMPACT_INLINE MaskN<N> select(MaskN<N> m, MaskN<N> a, MaskN<N> b) {
  return MaskN<N>((m.v & a.v) | (~m.v & b.v));
}
/// a & !b
template <uint32_t N>
IMPACT_INLINE MaskN<N> andnot(MaskN<N> a, MaskN<N> b) {
  return MaskN<N>(a.v & ~b.v);
}
/// 1 where m, else 0.
template <uint32_t N>
IMPACT_INLINE IntN<N> to_int(MaskN<N> m) {
  return IntN<N>(-m.v);
}
/// Each lane converted to float (rounded to nearest; exact below 2^24).
template <uint32_t N>
IMPACT_INLINE FloatN<N> to_float(IntN<N> i) {
  return FloatN<N>(__builtin_convertvector(i.v, typename FloatN<N>::Raw));
}

template <uint32_t N>
IMPACT_INLINE bool any(MaskN<N> m) {
#if defined(__AVX512F__)
  if constexpr (N == 16) {
    const __m512i v = reinterpret_cast<__m512i>(m.v);
    return _mm512_test_epi32_mask(v, v) != 0;
  }
#endif
#if defined(__AVX__)
  if constexpr (N == 8) return _mm256_movemask_ps(reinterpret_cast<__m256>(m.v)) != 0;
#endif
#if defined(__SSE2__)
  if constexpr (N == 4) return _mm_movemask_ps(reinterpret_cast<__m128>(m.v)) != 0;
#endif
  int32_t r = 0;
  for (uint32_t i = 0; i < N; ++i) r |= m.v[i];
  return r != 0;
}
template <uint32_t N>
IMPACT_INLINE bool all(MaskN<N> m) {
#if defined(__AVX512F__)
  if constexpr (N == 16) {
    const __m512i v = reinterpret_cast<__m512i>(m.v);
    return _mm512_test_epi32_mask(v, v) == 0xffff;
  }
#endif
#if defined(__AVX__)
  if constexpr (N == 8) return _mm256_movemask_ps(reinterpret_cast<__m256>(m.v)) == 0xff;
#endif
#if defined(__SSE2__)
  if constexpr (N == 4) return _mm_movemask_ps(reinterpret_cast<__m128>(m.v)) == 0xf;
#endif
  int32_t r = -1;
  for (uint32_t i = 0; i < N; ++i) r &= m.v[i];
  return r != 0;
}
template <uint32_t N>
IMPACT_INLINE bool none(MaskN<N> m) {
  return !any(m);
}
/// Bit i set where lane i is (N <= 32).
template <uint32_t N>
IMPACT_INLINE uint32_t bits(MaskN<N> m) {
#if defined(__AVX512F__)
  if constexpr (N == 16) {
    const __m512i v = reinterpret_cast<__m512i>(m.v);
    return static_cast<uint32_t>(_mm512_test_epi32_mask(v, v));
  }
#endif
#if defined(__AVX__)
  if constexpr (N == 8) return static_cast<uint32_t>(_mm256_movemask_ps(reinterpret_cast<__m256>(m.v)));
#endif
#if defined(__SSE2__)
  if constexpr (N == 4) return static_cast<uint32_t>(_mm_movemask_ps(reinterpret_cast<__m128>(m.v)));
#endif
  uint32_t r = 0;
  for (uint32_t i = 0; i < N; ++i) r |= (m.v[i] != 0 ? 1u : 0u) << i;
  return r;
}

/// bits(a < b) (ordered: false for NaN), at N = 16 under AVX-512 straight from the compare
/// into a mask register: GCC 12 otherwise widens the compare's mask to a vector and tests it
/// back (two more instructions on the loop's chain).
template <uint32_t N>
IMPACT_INLINE uint32_t bits_lt(FloatN<N> a, FloatN<N> b) {
#if defined(__AVX512F__)
  if constexpr (N == 16) {
    return static_cast<uint32_t>(
        _mm512_cmp_ps_mask(reinterpret_cast<__m512>(a.v), reinterpret_cast<__m512>(b.v), _CMP_LT_OS));
  }
#endif
#if defined(__AVX512F__) && defined(__AVX512VL__)
  if constexpr (N == 8) {
    return static_cast<uint32_t>(
        _mm256_cmp_ps_mask(reinterpret_cast<__m256>(a.v), reinterpret_cast<__m256>(b.v), _CMP_LT_OS));
  }
#endif
  return bits(a < b);
}
/// Expand: for each set bit l of `bits` (l < N), in order, dst[l] = the next of src[0],
/// src[1], ...; dst[l] for clear bits is not written (the inverse of compacting the set
/// lanes). AVX-512 at N = 16: one expanding load and one masked store.
template <uint32_t N>
IMPACT_INLINE void expand_store(float* dst, const float* src, uint32_t bits) {
#if defined(__AVX512F__)
  if constexpr (N == 16) {
    const auto k = static_cast<__mmask16>(bits);
    _mm512_mask_storeu_ps(dst, k, _mm512_maskz_expandloadu_ps(k, src));
    return;
  }
#endif
  for (uint32_t i = 0; bits != 0; ++i, bits &= bits - 1u) dst[__builtin_ctz(bits)] = src[i];
}
/// Compact (the inverse of expand_store): the lanes of v whose bit is set in `bits`
/// (bits < 2^N), in lane order, to dst[0 .. popcount(bits)); returns that count. It may
/// write dst[count .. N) as well, so dst must hold N entries. Branch-free: AVX-512 at
/// N = 16 compresses in a register and stores all 16 (the memory form is microcoded on
/// some cores); elsewhere every lane is written and the cursor advances on set bits.
template <uint32_t N>
IMPACT_INLINE uint32_t compact_store(int32_t* dst, IntN<N> v, uint32_t bits) {
#if defined(__AVX512F__)
  if constexpr (N == 16) {
    const auto k = static_cast<__mmask16>(bits);
    _mm512_storeu_si512(dst, _mm512_maskz_compress_epi32(k, reinterpret_cast<__m512i>(v.v)));
    return static_cast<uint32_t>(__builtin_popcount(bits));
  }
#endif
#if defined(__AVX512F__) && defined(__AVX512VL__)
  if constexpr (N == 8) {
    const auto k = static_cast<__mmask8>(bits);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst),
                        _mm256_maskz_compress_epi32(k, reinterpret_cast<__m256i>(v.v)));
    return static_cast<uint32_t>(__builtin_popcount(bits));
  }
#endif
  uint32_t c = 0;
  for (uint32_t l = 0; l < N; ++l) {
    dst[c] = v.v[l];
    c += (bits >> l) & 1u;
  }
  return c;
}
/// expand_store for small counts: int32 src narrowed to uint8 dst (values 0 .. 255).
template <uint32_t N>
IMPACT_INLINE void expand_store(uint8_t* dst, const int32_t* src, uint32_t bits) {
#if defined(__AVX512F__)
  if constexpr (N == 16) {
    const auto k = static_cast<__mmask16>(bits);
    _mm512_mask_cvtepi32_storeu_epi8(dst, k, _mm512_maskz_expandloadu_epi32(k, src));
    return;
  }
#endif
  for (uint32_t i = 0; bits != 0; ++i, bits &= bits - 1u) dst[__builtin_ctz(bits)] = static_cast<uint8_t>(src[i]);
}

template <uint32_t N>
IMPACT_INLINE FloatN<N> min(FloatN<N> a, FloatN<N> b) {
#if defined(__AVX__)
  if constexpr (N == 8) return FloatN<N>(reinterpret_cast<typename FloatN<N>::Raw>(_mm256_min_ps(a.v, b.v)));
#endif
#if defined(__SSE2__)
  if constexpr (N == 4) return FloatN<N>(reinterpret_cast<typename FloatN<N>::Raw>(_mm_min_ps(a.v, b.v)));
#endif
  return FloatN<N>(a.v < b.v ? a.v : b.v);
}
template <uint32_t N>
IMPACT_INLINE FloatN<N> max(FloatN<N> a, FloatN<N> b) {
#if defined(__AVX__)
  if constexpr (N == 8) return FloatN<N>(reinterpret_cast<typename FloatN<N>::Raw>(_mm256_max_ps(a.v, b.v)));
#endif
#if defined(__SSE2__)
  if constexpr (N == 4) return FloatN<N>(reinterpret_cast<typename FloatN<N>::Raw>(_mm_max_ps(a.v, b.v)));
#endif
  return FloatN<N>(a.v > b.v ? a.v : b.v);
}
template <uint32_t N>
IMPACT_INLINE FloatN<N> sqrt(FloatN<N> a) {
#if defined(__AVX512F__)
  if constexpr (N == 16) return FloatN<N>(reinterpret_cast<typename FloatN<N>::Raw>(_mm512_maskz_sqrt_ps(0xffff, a.v)));
#endif
#if defined(__AVX__)
  if constexpr (N == 8) return FloatN<N>(reinterpret_cast<typename FloatN<N>::Raw>(_mm256_sqrt_ps(a.v)));
#endif
#if defined(__SSE2__)
  if constexpr (N == 4) return FloatN<N>(reinterpret_cast<typename FloatN<N>::Raw>(_mm_sqrt_ps(a.v)));
#endif
  FloatN<N> r;
  for (uint32_t i = 0; i < N; ++i) r.v[i] = std::sqrt(a.v[i]);
  return r;
}
template <uint32_t N>
IMPACT_INLINE FloatN<N> abs(FloatN<N> a) {
  using I = typename FloatN<N>::IRaw;
  return FloatN<N>(reinterpret_cast<typename FloatN<N>::Raw>(reinterpret_cast<I>(a.v) & 0x7fffffff));
}

/// Lane i of arr[idx_i] for every lane i (idx_i in [0, count of arr)): the per-lane pick
/// of a candidate from an array of lanes.
template <uint32_t N>
IMPACT_INLINE FloatN<N> gather_lanes(const FloatN<N>* arr, IntN<N> idx) {
#if defined(__AVX512F__)
  if constexpr (N == 16) {
    using I = typename IntN<N>::Raw;
    const I lane = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15};
    const __m512i vi = reinterpret_cast<__m512i>(idx.v * 16 + lane);
    return FloatN<N>(reinterpret_cast<typename FloatN<N>::Raw>(
        _mm512_mask_i32gather_ps(_mm512_setzero_ps(), 0xffff, vi, reinterpret_cast<const float*>(arr), 4)));
  }
#endif
#if defined(__AVX2__)
  if constexpr (N == 8) {
    const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    const __m256i vi = _mm256_add_epi32(_mm256_slli_epi32(reinterpret_cast<__m256i>(idx.v), 3), lane);
    return FloatN<N>(reinterpret_cast<typename FloatN<N>::Raw>(
        _mm256_i32gather_ps(reinterpret_cast<const float*>(arr), vi, 4)));
  }
#endif
  FloatN<N> r;
  for (uint32_t i = 0; i < N; ++i) r.v[i] = arr[idx.v[i]].v[i];
  return r;
}

/// base[idx_i] in lane i (a gather from one array by per-lane indices).
/// (AVX2: vgatherdps merges into its destination register, so the destination's old
/// value is an input. With _mm256_i32gather_ps, or a constant all-ones mask, GCC gathers
/// into whatever register it picks, at times one that holds the previous loop
/// iteration's last result, and the iterations then run one after the other. So the
/// mask is hidden from the optimiser and the source is a fresh zero, which breaks that
/// dependency.)
template <uint32_t N>
IMPACT_INLINE FloatN<N> gather(const float* base, IntN<N> idx) {
#if defined(__AVX512F__)
  if constexpr (N == 16) {
    __mmask16 mask = 0xffff;
    __asm__("" : "+k"(mask));
    return FloatN<N>(reinterpret_cast<typename FloatN<N>::Raw>(
        _mm512_mask_i32gather_ps(_mm512_setzero_ps(), mask, reinterpret_cast<__m512i>(idx.v), base, 4)));
  }
#endif
#if defined(__AVX2__)
  if constexpr (N == 8) {
    __m256 mask = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
    __asm__("" : "+x"(mask));
    return FloatN<N>(reinterpret_cast<typename FloatN<N>::Raw>(
        _mm256_mask_i32gather_ps(_mm256_setzero_ps(), base, reinterpret_cast<__m256i>(idx.v), mask, 4)));
  }
#endif
  FloatN<N> r;
  for (uint32_t i = 0; i < N; ++i) r.v[i] = base[idx.v[i]];
  return r;
}

/// base[idx_i] in lane i for several arrays base and one index vector, every idx_i in
/// [begin, end) where each array may be read. Meant for a chunk's live lanes listed in
/// order (ascending, close together): at 16 lanes (AVX-512), when every lane lies in
/// [idx_0, idx_0 + 64), each array is read as one or two 32-float windows inside
/// [begin, end) (the last one ending at end at most), each two loads and a two-source
/// permute (vpermt2ps), where a 16-lane gather costs ~17 cycles on AMD Zen 4; otherwise
/// (other widths, lanes out of order or farther apart, ranges under 32) by gather().
/// The same values either way.
template <uint32_t N>
class SortedGather {
 public:
  IMPACT_INLINE SortedGather(IntN<N> idx, int32_t begin, int32_t end) : idx_(idx) {
#if defined(__AVX512F__)
    if constexpr (N == 16) {
      const __m512i i = reinterpret_cast<__m512i>(idx.v), k32 = _mm512_set1_epi32(32);
      const int32_t lo = idx.v[0];
      const int32_t w0 = lo < end - 32 ? lo : end - 32, w1 = w0 + 32 < end - 32 ? w0 + 32 : end - 32;
      w_[0] = w0, w_[1] = w1;
      rel_[0] = _mm512_sub_epi32(i, _mm512_set1_epi32(w0));
      rel_[1] = _mm512_sub_epi32(i, _mm512_set1_epi32(w1));
      in1_ = _mm512_cmpge_epu32_mask(rel_[0], k32);  // not in window 0 (below it too)
      const __mmask16 out = _mm512_mask_cmpge_epu32_mask(in1_, rel_[1], k32);
      windows_ = end - begin < 32 || lo < begin || out != 0 ? 0 : in1_ != 0 ? 2 : 1;
    }
#else
    (void)begin, (void)end;
#endif
  }
  IMPACT_INLINE FloatN<N> operator()(const float* base) const {
#if defined(__AVX512F__)
    if constexpr (N == 16) {
      if (windows_ != 0) {
        using Raw = typename FloatN<N>::Raw;
        auto window = [&](int w) {
          return _mm512_permutex2var_ps(_mm512_loadu_ps(base + w_[w]), rel_[w],
                                        _mm512_loadu_ps(base + w_[w] + 16));
        };
        __m512 r = window(0);
        if (windows_ == 2) r = _mm512_mask_mov_ps(r, in1_, window(1));
        return FloatN<N>(reinterpret_cast<Raw>(r));
      }
    }
#endif
    return gather(base, idx_);
  }

 private:
  IntN<N> idx_;
#if defined(__AVX512F__)
  int32_t windows_ = 0;  // 0: gather
  int32_t w_[2] = {0, 0};
  __m512i rel_[2];
  __mmask16 in1_ = 0;
#endif
};

/// Lane i of out[c] = base[stride idx[i] + c], c < 4: four consecutive floats of
/// records `stride` floats apart, one 16-byte load a lane and a 4 x 4 transpose per
/// 128-bit chunk instead of four gathers (a 16-lane gather on AMD Zen 4 costs ~17
/// cycles). No alignment needed; the 4 floats must be readable.
template <uint32_t N>
IMPACT_INLINE void gather4(const float* base, int32_t stride, const int32_t* idx, FloatN<N>* out) {
#if defined(__SSE2__)
  using Raw = typename FloatN<N>::Raw;
  auto rec = [&](uint32_t l) {
    return _mm_loadu_ps(base + static_cast<int64_t>(stride) * static_cast<int64_t>(idx[l]));
  };
#endif
#if defined(__AVX512F__)
  if constexpr (N == 16) {
    auto four = [&](uint32_t l) {  // lanes l, l + 4, l + 8, l + 12 in chunks 0 .. 3
      __m512 r = _mm512_zextps128_ps512(rec(l));
      r = _mm512_insertf32x4(r, rec(l + 4), 1);
      r = _mm512_insertf32x4(r, rec(l + 8), 2);
      return _mm512_insertf32x4(r, rec(l + 12), 3);
    };
    const __m512 a = four(0), b = four(1), c = four(2), d = four(3);
    // (The maskz forms: GCC 12's plain unpack takes an "undefined" source that
    // -Wmaybe-uninitialized reports; an all-ones mask compiles to the plain instruction.)
    const __m512 ab0 = _mm512_maskz_unpacklo_ps(0xffff, a, b), ab1 = _mm512_maskz_unpackhi_ps(0xffff, a, b);
    const __m512 cd0 = _mm512_maskz_unpacklo_ps(0xffff, c, d), cd1 = _mm512_maskz_unpackhi_ps(0xffff, c, d);
    out[0] = FloatN<N>(reinterpret_cast<Raw>(_mm512_shuffle_ps(ab0, cd0, 0x44)));
    out[1] = FloatN<N>(reinterpret_cast<Raw>(_mm512_shuffle_ps(ab0, cd0, 0xee)));
    out[2] = FloatN<N>(reinterpret_cast<Raw>(_mm512_shuffle_ps(ab1, cd1, 0x44)));
    out[3] = FloatN<N>(reinterpret_cast<Raw>(_mm512_shuffle_ps(ab1, cd1, 0xee)));
    return;
  }
#endif
#if defined(__AVX__)
  if constexpr (N == 8) {
    auto two = [&](uint32_t l) { return _mm256_set_m128(rec(l + 4), rec(l)); };
    const __m256 a = two(0), b = two(1), c = two(2), d = two(3);
    const __m256 ab0 = _mm256_unpacklo_ps(a, b), ab1 = _mm256_unpackhi_ps(a, b);
    const __m256 cd0 = _mm256_unpacklo_ps(c, d), cd1 = _mm256_unpackhi_ps(c, d);
    out[0] = FloatN<N>(reinterpret_cast<Raw>(_mm256_shuffle_ps(ab0, cd0, 0x44)));
    out[1] = FloatN<N>(reinterpret_cast<Raw>(_mm256_shuffle_ps(ab0, cd0, 0xee)));
    out[2] = FloatN<N>(reinterpret_cast<Raw>(_mm256_shuffle_ps(ab1, cd1, 0x44)));
    out[3] = FloatN<N>(reinterpret_cast<Raw>(_mm256_shuffle_ps(ab1, cd1, 0xee)));
    return;
  }
#endif
#if defined(__SSE2__)
  if constexpr (N == 4) {
    const __m128 a = rec(0), b = rec(1), c = rec(2), d = rec(3);
    const __m128 ab0 = _mm_unpacklo_ps(a, b), ab1 = _mm_unpackhi_ps(a, b);
    const __m128 cd0 = _mm_unpacklo_ps(c, d), cd1 = _mm_unpackhi_ps(c, d);
    out[0] = FloatN<N>(reinterpret_cast<Raw>(_mm_movelh_ps(ab0, cd0)));
    out[1] = FloatN<N>(reinterpret_cast<Raw>(_mm_movehl_ps(cd0, ab0)));
    out[2] = FloatN<N>(reinterpret_cast<Raw>(_mm_movelh_ps(ab1, cd1)));
    out[3] = FloatN<N>(reinterpret_cast<Raw>(_mm_movehl_ps(cd1, ab1)));
    return;
  }
  (void)rec;
#endif
  for (uint32_t i = 0; i < N; ++i) {
    const float* r = base + static_cast<int64_t>(stride) * static_cast<int64_t>(idx[i]);
    for (uint32_t c = 0; c < 4; ++c) out[c].v[i] = r[c];
  }
}

/// Lane i of x, y, z = xyzw[4 idx[i] + 0, 1, 2]: records of 4 floats (x, y, z and one
/// unused), by gather4 instead of three gathers.
template <uint32_t N>
IMPACT_INLINE void gather_xyz(const float* xyzw, const int32_t* idx, FloatN<N>* x, FloatN<N>* y,
                              FloatN<N>* z) {
  FloatN<N> r[4];
  gather4(xyzw, 4, idx, r);
  *x = r[0], *y = r[1], *z = r[2];
}

/// out[j] lane i = rows[i][j] for i, j < N: N rows of N contiguous floats (one row per
/// lane, no alignment needed), transposed; the per-lane walk over a short array without
/// gathers (N loads and a shuffle network: 24 shuffles for N = 8, where 8 gathers cost
/// several times that).
#if defined(__AVX__)
/// o = the 8 x 8 transpose of r (row i of r is register r[i]): unpacks, shuffles and
/// 128-bit permutes, no memory. load_transposed and store_transposed share it.
IMPACT_INLINE void transpose8(const __m256 r[8], __m256 o[8]) {
    const __m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpackhi_ps(r[0], r[1]);
    const __m256 t2 = _mm256_unpacklo_ps(r[2], r[3]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
    const __m256 t4 = _mm256_unpacklo_ps(r[4], r[5]), t5 = _mm256_unpackhi_ps(r[4], r[5]);
    const __m256 t6 = _mm256_unpacklo_ps(r[6], r[7]), t7 = _mm256_unpackhi_ps(r[6], r[7]);
    const __m256 s0 = _mm256_shuffle_ps(t0, t2, 0x44), s1 = _mm256_shuffle_ps(t0, t2, 0xee);
    const __m256 s2 = _mm256_shuffle_ps(t1, t3, 0x44), s3 = _mm256_shuffle_ps(t1, t3, 0xee);
    const __m256 s4 = _mm256_shuffle_ps(t4, t6, 0x44), s5 = _mm256_shuffle_ps(t4, t6, 0xee);
    const __m256 s6 = _mm256_shuffle_ps(t5, t7, 0x44), s7 = _mm256_shuffle_ps(t5, t7, 0xee);
    const __m256 x[8] = {_mm256_permute2f128_ps(s0, s4, 0x20), _mm256_permute2f128_ps(s1, s5, 0x20),
                         _mm256_permute2f128_ps(s2, s6, 0x20), _mm256_permute2f128_ps(s3, s7, 0x20),
                         _mm256_permute2f128_ps(s0, s4, 0x31), _mm256_permute2f128_ps(s1, s5, 0x31),
                         _mm256_permute2f128_ps(s2, s6, 0x31), _mm256_permute2f128_ps(s3, s7, 0x31)};
    for (int j = 0; j < 8; ++j) o[j] = x[j];
}
#endif

template <uint32_t N>
IMPACT_INLINE void load_transposed(const float* const* rows, FloatN<N>* out) {
#if defined(__AVX__)
  if constexpr (N == 8) {
    __m256 r[8];
    for (int i = 0; i < 8; ++i) r[i] = _mm256_loadu_ps(rows[i]);
    __m256 o[8];
    transpose8(r, o);
    for (int j = 0; j < 8; ++j) out[j] = FloatN<N>(reinterpret_cast<typename FloatN<N>::Raw>(o[j]));
    return;
  }
#endif
  for (uint32_t j = 0; j < N; ++j)
    for (uint32_t i = 0; i < N; ++i) out[j].v[i] = rows[i][j];
}

/// The inverse of load_transposed for the rows whose bit is set in `bits`: rows[i][j] =
/// lane i of in[j] for i, j < N where bit i is set; rows with a clear bit are not
/// touched (not even rewritten with their own values, so a row shared by several lanes
/// or threads, read-only to them, is never written). The per-lane scatter of short
/// records (a constraint's bodies) after a wide update.
template <uint32_t N>
IMPACT_INLINE void store_transposed(float* const* rows, const FloatN<N>* in, uint32_t bits) {
#if defined(__AVX__)
  if constexpr (N == 8) {
    __m256 r[8];
    for (int j = 0; j < 8; ++j) r[j] = reinterpret_cast<__m256>(in[j].v);
    // The 8 x 8 transpose is its own inverse.
    __m256 o[8];
    transpose8(r, o);
    for (int i = 0; i < 8; ++i) {
#if defined(__AVX512F__) && defined(__AVX512VL__)
      // A masked store with an empty mask writes nothing (and does not fault).
      _mm256_mask_storeu_ps(rows[i], static_cast<__mmask8>(-((bits >> i) & 1u)), o[i]);
#else
      if ((bits >> i) & 1u) _mm256_storeu_ps(rows[i], o[i]);
#endif
    }
    return;
  }
#endif
  for (uint32_t i = 0; i < N; ++i)
    if ((bits >> i) & 1u)
      for (uint32_t j = 0; j < N; ++j) rows[i][j] = in[j].v[i];
}

/// key with its 5 low mantissa bits replaced by index i in [0, 32) (a relative change
/// below 4e-6; among exactly equal positive keys the lower index compares larger).
template <uint32_t N>
IMPACT_INLINE FloatN<N> tag(FloatN<N> key, int32_t i) {
  using I = typename FloatN<N>::IRaw;
  const I b = (reinterpret_cast<I>(key.v) & ~31) | (31 - i);
  return FloatN<N>(reinterpret_cast<typename FloatN<N>::Raw>(b));
}
/// The index a tag() put in key.
template <uint32_t N>
IMPACT_INLINE IntN<N> tag_index(FloatN<N> key) {
  using I = typename FloatN<N>::IRaw;
  return IntN<N>(31 - (reinterpret_cast<I>(key.v) & 31));
}

// ---------------------------------------------------------------------------------------
// N == 1: the scalar reference path, plain float / bool / int32.
// ---------------------------------------------------------------------------------------

template <>
struct MaskN<1> {
  static constexpr uint32_t kWidth = 1;
  bool v;
  MaskN() = default;
  IMPACT_INLINE explicit MaskN(bool b) : v(b) {}
  IMPACT_INLINE bool lane(uint32_t) const { return v; }
  friend IMPACT_INLINE MaskN operator&(MaskN a, MaskN b) { return MaskN(a.v && b.v); }
  friend IMPACT_INLINE MaskN operator|(MaskN a, MaskN b) { return MaskN(a.v || b.v); }
  friend IMPACT_INLINE MaskN operator^(MaskN a, MaskN b) { return MaskN(a.v != b.v); }
  friend IMPACT_INLINE MaskN operator~(MaskN a) { return MaskN(!a.v); }
};

template <>
struct IntN<1> {
  static constexpr uint32_t kWidth = 1;
  int32_t v;
  IntN() = default;
  IMPACT_INLINE IntN(int32_t s) : v(s) {}
  static IMPACT_INLINE IntN load(const int32_t* p) { return IntN(*p); }
  IMPACT_INLINE void store(int32_t* p) const { *p = v; }
  IMPACT_INLINE int32_t lane(uint32_t) const { return v; }
  friend IMPACT_INLINE IntN operator+(IntN a, IntN b) { return IntN(a.v + b.v); }
  friend IMPACT_INLINE IntN operator-(IntN a, IntN b) { return IntN(a.v - b.v); }
  friend IMPACT_INLINE IntN operator&(IntN a, IntN b) { return IntN(a.v & b.v); }
  friend IMPACT_INLINE IntN operator>>(IntN a, int s) { return IntN(a.v >> s); }
  friend IMPACT_INLINE MaskN<1> operator==(IntN a, IntN b) { return MaskN<1>(a.v == b.v); }
  friend IMPACT_INLINE MaskN<1> operator>(IntN a, IntN b) { return MaskN<1>(a.v > b.v); }
};

template <>
struct FloatN<1> {
  static constexpr uint32_t kWidth = 1;
  using Mask = MaskN<1>;
  using Int = IntN<1>;
  float v;

  FloatN() = default;
  IMPACT_INLINE FloatN(float s) : v(s) {}

  static IMPACT_INLINE FloatN load(const float* p) { return FloatN(*p); }
  IMPACT_INLINE void store(float* p) const { *p = v; }
  IMPACT_INLINE float lane(uint32_t) const { return v; }

  IMPACT_FLOAT_LANE_OPERATORS
};

#undef IMPACT_FLOAT_LANE_OPERATORS

IMPACT_INLINE FloatN<1> select(MaskN<1> m, FloatN<1> a, FloatN<1> b) { return m.v ? a : b; }
IMPACT_INLINE IntN<1> select(MaskN<1> m, IntN<1> a, IntN<1> b) { return m.v ? a : b; }
IMPACT_INLINE MaskN<1> select(MaskN<1> m, MaskN<1> a, MaskN<1> b) { return m.v ? a : b; }
IMPACT_INLINE MaskN<1> andnot(MaskN<1> a, MaskN<1> b) { return MaskN<1>(a.v && !b.v); }
IMPACT_INLINE IntN<1> to_int(MaskN<1> m) { return IntN<1>(m.v ? 1 : 0); }
IMPACT_INLINE FloatN<1> to_float(IntN<1> i) {
  return FloatN<1>(static_cast<float>(i.v));
}
IMPACT_INLINE bool any(MaskN<1> m) { return m.v; }
IMPACT_INLINE bool all(MaskN<1> m) { return m.v; }
IMPACT_INLINE bool none(MaskN<1> m) { return !m.v; }
IMPACT_INLINE uint32_t bits(MaskN<1> m) { return m.v ? 1u : 0u; }
IMPACT_INLINE uint32_t bits_lt(FloatN<1> a, FloatN<1> b) { return a.v < b.v ? 1u : 0u; }
template <>
IMPACT_INLINE uint32_t compact_store<1>(int32_t* dst, IntN<1> v, uint32_t bits) {
  dst[0] = v.v;
  return bits & 1u;
}
// Same operand order as the x86 instructions, so both paths agree bit for bit.
IMPACT_INLINE FloatN<1> min(FloatN<1> a, FloatN<1> b) { return a.v < b.v ? a : b; }
IMPACT_INLINE FloatN<1> max(FloatN<1> a, FloatN<1> b) { return a.v > b.v ? a : b; }
IMPACT_INLINE FloatN<1> sqrt(FloatN<1> a) { return FloatN<1>(std::sqrt(a.v)); }
IMPACT_INLINE FloatN<1> abs(FloatN<1> a) { return FloatN<1>(std::fabs(a.v)); }

IMPACT_INLINE FloatN<1> gather(const float* base, IntN<1> idx) { return FloatN<1>(base[idx.v]); }
IMPACT_INLINE FloatN<1> gather_lanes(const FloatN<1>* arr, IntN<1> idx) { return arr[idx.v]; }
IMPACT_INLINE void load_transposed(const float* const* rows, FloatN<1>* out) { out[0] = FloatN<1>(rows[0][0]); }
IMPACT_INLINE void store_transposed(float* const* rows, const FloatN<1>* in, uint32_t bits) {
  if (bits & 1u) rows[0][0] = in[0].v;
}
template <>
class SortedGather<1> {
 public:
  IMPACT_INLINE SortedGather(IntN<1> idx, int32_t, int32_t) : idx_(idx) {}
  IMPACT_INLINE FloatN<1> operator()(const float* base) const { return FloatN<1>(base[idx_.v]); }

 private:
  IntN<1> idx_;
};
IMPACT_INLINE void gather4(const float* base, int32_t stride, const int32_t* idx, FloatN<1>* out) {
  const float* r = base + static_cast<int64_t>(stride) * static_cast<int64_t>(idx[0]);
  for (int c = 0; c < 4; ++c) out[c] = FloatN<1>(r[c]);
}
IMPACT_INLINE FloatN<1> tag(FloatN<1> key, int32_t i) {
  uint32_t b;
  std::memcpy(&b, &key.v, 4);
  b = (b & ~31u) | static_cast<uint32_t>(31 - i);
  float f;
  std::memcpy(&f, &b, 4);
  return FloatN<1>(f);
}
IMPACT_INLINE IntN<1> tag_index(FloatN<1> key) {
  uint32_t b;
  std::memcpy(&b, &key.v, 4);
  return IntN<1>(31 - static_cast<int32_t>(b & 31u));
}

// ---------------------------------------------------------------------------------------
// Shared verbs and the two instantiations.
// ---------------------------------------------------------------------------------------

/// a * b + c. Written plainly: the build's -ffp-contract decides whether it fuses,
/// the same way for both paths (IMPACT_STRICT_FP turns fusion off everywhere).
template <class F>
IMPACT_INLINE F mul_add(F a, F b, F c) {
  return a * b + c;
}
template <class F>
IMPACT_INLINE F clamp(F x, F lo, F hi) {
  return min(max(x, lo), hi);
}
/// +1 where x >= 0 (also +0 and -0), else -1.
template <class F>
IMPACT_INLINE F sign_nonneg(F x) {
  return select(x >= F(0.0f), F(1.0f), F(-1.0f));
}

/// min / max of non-NaN floats, inlined (std::fmin / fmax are libm calls here).
IMPACT_INLINE float fmin_nn(float a, float b) { return b < a ? b : a; }
IMPACT_INLINE float fmax_nn(float a, float b) { return b > a ? b : a; }

/// 0, 1, ..., W - 1: each lane's own index.
template <class F>
IMPACT_INLINE F lane_index() {
  float iota[F::kWidth];
  for (uint32_t k = 0; k < F::kWidth; ++k) iota[k] = static_cast<float>(k);
  return F::load(iota);
}

/// base, base + 1, ..., base + W - 1 as int lanes (a block's chunk lane indices).
template <class I>
IMPACT_INLINE I lane_ids(int32_t base) {
  int32_t ids[I::kWidth];
  for (uint32_t k = 0; k < I::kWidth; ++k) ids[k] = base + static_cast<int32_t>(k);
  return I::load(ids);
}

/// Every lane = op folded over all of a's lanes (op associative and commutative, e.g.
/// max or min): log2(W) butterfly steps, each a shuffle that swaps lane i with lane
/// i ^ step. For W > 1.
template <class F, class Op>
IMPACT_INLINE F all_lanes(F a, Op op) {
  auto v = a.v;
  if constexpr (F::kWidth == 16) {
    v = op(F(v), F(__builtin_shufflevector(v, v, 8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2, 3, 4, 5, 6, 7))).v;
    v = op(F(v), F(__builtin_shufflevector(v, v, 4, 5, 6, 7, 0, 1, 2, 3, 12, 13, 14, 15, 8, 9, 10, 11))).v;
    v = op(F(v), F(__builtin_shufflevector(v, v, 2, 3, 0, 1, 6, 7, 4, 5, 10, 11, 8, 9, 14, 15, 12, 13))).v;
    v = op(F(v), F(__builtin_shufflevector(v, v, 1, 0, 3, 2, 5, 4, 7, 6, 9, 8, 11, 10, 13, 12, 15, 14))).v;
  } else if constexpr (F::kWidth == 8) {
    v = op(F(v), F(__builtin_shufflevector(v, v, 4, 5, 6, 7, 0, 1, 2, 3))).v;
    v = op(F(v), F(__builtin_shufflevector(v, v, 2, 3, 0, 1, 6, 7, 4, 5))).v;
    v = op(F(v), F(__builtin_shufflevector(v, v, 1, 0, 3, 2, 5, 4, 7, 6))).v;
  } else {
    static_assert(F::kWidth == 4, "all_lanes: widths 4, 8, 16");
    v = op(F(v), F(__builtin_shufflevector(v, v, 2, 3, 0, 1))).v;
    v = op(F(v), F(__builtin_shufflevector(v, v, 1, 0, 3, 2))).v;
  }
  return F(v);
}

/// The end of a lane-parallel argmax: the largest score s over the lanes, and in
/// *out_idx the lowest idx among the lanes that hold it (none: where no lane does,
/// i.e. NaN scores only; a NaN beside numbers may be ignored or returned).
/// Branch-free in the data, so the same bytes for any order. all_lanes butterflies
/// for the maximum and for the index (a lane-by-lane loop is a chain of 2W dependent
/// compares, the larger part of a short pass's cost).
template <class F>
IMPACT_INLINE float max_lowest_index(F s, F idx, float none, float* out_idx) {
  if constexpr (F::kWidth == 1) {
    const bool ok = s.lane(0) == s.lane(0);
    *out_idx = ok ? idx.lane(0) : none;
    return s.lane(0);
  } else {
    const F bs = all_lanes(s, [](F a, F b) { return max(a, b); });
    const F bi = all_lanes(select(s == bs, idx, F(none)), [](F a, F b) { return min(a, b); });
    *out_idx = bi.lane(0);
    return bs.lane(0);
  }
}

/// Lanes i .. i + W of p[0 .. n) (i < n), an index past n - 1 reading p[n - 1]: a pass
/// over n items in whole blocks (a repeated item changes no minimum or maximum). The
/// last block of n >= W items is the load of p[n - W ..] with its lanes moved into place
/// (GCC: one permute; building it from W scalar stores and a vector load would stall on
/// store forwarding).
template <class F>
IMPACT_INLINE F load_clamped(const float* p, uint32_t i, uint32_t n) {
  constexpr uint32_t W = F::kWidth;
  if (i + W <= n) return F::load(p + i);
#if defined(__GNUC__) && !defined(__clang__)
  if constexpr (W > 1) {
    if (n >= W) {
      // Lane k takes item min(i + k, n - 1), which sits at lane min(i + k, n - 1) - (n - W).
      using I = typename F::Int;
      const I at = lane_ids<I>(static_cast<int32_t>(i + W - n));
      const I last(static_cast<int32_t>(W - 1));
      const I idx = select(at > last, last, at);
      return F(__builtin_shuffle(F::load(p + n - W).v, idx.v));
    }
  }
#endif
  float t[W];
  for (uint32_t k = 0; k < W; ++k) t[k] = p[i + k < n ? i + k : n - 1];
  return F::load(t);
}

using FloatW = FloatN<kSimdWidth>;

/// The widest lanes the target has: 16 where AVX-512F is enabled (one zmm register),
/// else kSimdWidth. For passes whose wide vectors pay (the LBVH pair walk's box tests).
#if !defined(IMPACT_SIMD_SCALAR) && defined(__AVX512F__)
inline constexpr uint32_t kWideWidth = 16;
#else
inline constexpr uint32_t kWideWidth = kSimdWidth;
#endif

/// Lanes of the kernels that put one pair per lane (sphere, capsule, box, cylinder,
/// ellipsoid and triangle pairs, and hull-half-space, whose lanes each walk their own
/// hull's vertices a vector at a time): kWideWidth unless IMPACT_PAIR_LANES8 is defined,
/// else kSimdWidth. Kernels that walk one hull's features a vector at a time keep
/// kSimdWidth (their walks take a per-item path below one vector's worth of features,
/// which 16 lanes would send most small hulls to; measured in docs/narrowphase.md).
/// Every verb is lane-wise, so a pair's bytes do not depend on the width.
#if defined(IMPACT_PAIR_LANES8)
inline constexpr uint32_t kPairWidth = kSimdWidth;
#else
inline constexpr uint32_t kPairWidth = kWideWidth;
#endif
using FloatP = FloatN<kPairWidth>;
using MaskW = MaskN<kSimdWidth>;
using IntW = IntN<kSimdWidth>;
using Float1 = FloatN<1>;
using Mask1 = MaskN<1>;
using Int1 = IntN<1>;

}  // namespace impact::kernels::simd
