// rtp's SIMD vocabulary: the lane types the engine computes in, and the few operations on them.
//
// This is the only file that knows instruction sets: no other source has an instruction-set #if,
// a target attribute or an intrinsic (which is why it is long: each operation's every instruction
// set, side by side, so that a reader compares them in one place). Two kinds of type:
//
//   Pack<T, N>, Mask<T, N>  N lanes of T, and a mask of the same shape whose lanes are all ones
//                           or zero: the narrow phase's 4 and 8 doubles and the broad phase's
//                           native-width floats. With SIMD these are GCC's vector-extension types
//                           themselves (one register, or several halves on a narrower core: the
//                           compiler splits them), so +, −, ×, ÷, comparisons and &, |, ^, ~ are
//                           the compiler's own and an expression keeps its order of evaluation
//                           (an overloaded operator's operands may be evaluated in either order,
//                           which changes which product a multiply-add fuses where FMA is on).
//                           4 and 8 doubles and 8 floats on the x86-64 baseline are the exception:
//                           Split, SSE2 halves with operators of their own (no FMA there to fuse).
//                           Without SIMD they are structs of arrays with the same operators.
//   Float16, Mask16         16 floats in one AVX-512 register and a 16-bit lane mask, for the
//                           particle kernels, which run on cores found at run time to have
//                           AVX-512F in a build that may target less: their operations carry the
//                           target attribute (RTP_SIMD_TARGET_AVX512 marks the kernels that use
//                           them), and core_has_avx512() is the one run-time check.
//
// Every operation has a scalar fallback, a loop over the lanes computing the same thing lane by
// lane. The CMake option RTP_DISABLE_SIMD defines RTP_DISABLE_SIMD and builds the engine on the
// fallbacks alone: no vector type, no intrinsic (the compiler may still vectorise plain loops).
// Results are the same bit for bit, lane for lane — the lane arithmetic is IEEE either way — except
// the AVX-512 estimates (rsqrt14, rcp14), which have no scalar twin; the particle kernels that use
// them are never chosen without SIMD (core_has_avx512() is false), and their fallbacks compute
// exact 1/√x and 1/x so that the code still builds and reads the same.
//
// Modelled on Box2D v3's b2FloatW (a lane type per instruction set, each operation written once
// per set with a scalar version) and Jolt's Vec4 (a register with operators).
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <type_traits>
#include <utility>

#if !defined(RTP_DISABLE_SIMD) && defined(__GNUC__)
#define RTP_SIMD_VECTORS 1  // GCC's vector extension (GCC and Clang)
#if defined(__x86_64__)
#include <immintrin.h>
#define RTP_SIMD_AVX512_KERNELS 1  // the particle kernels' Float16 is an AVX-512 register
#endif
#endif

#ifdef RTP_SIMD_AVX512_KERNELS
#define RTP_SIMD_TARGET_AVX512 __attribute__((target("avx512f")))
#else
#define RTP_SIMD_TARGET_AVX512
#endif

namespace rtp::simd {

// the instruction set the build targets, in words (rtp::instruction_set())
inline constexpr const char* kInstructionSet =
#if defined(RTP_DISABLE_SIMD)
    "no vector code (RTP_DISABLE_SIMD: simd.h's scalar fallbacks)";
#elif defined(__AVX512F__) && defined(__FMA__)
    "AVX-512F, AVX2, FMA";
#elif defined(__AVX2__) && defined(__FMA__)
    "AVX2, FMA";
#elif defined(__AVX__)
    "AVX";
#elif defined(__x86_64__)
    "x86-64 baseline (SSE2)";
#else
    "the target's baseline";
#endif

// the integer of a lane's width: what a mask lane holds
template <typename T>
using LaneInt = std::conditional_t<sizeof(T) == 8, std::int64_t, std::int32_t>;

#ifdef RTP_SIMD_VECTORS
// N lanes of T in the vector extension (the attribute, written so, may depend on the template)
template <typename T, std::size_t N>
struct VectorOf {
  using type [[gnu::vector_size(N * sizeof(T))]] = T;
};
#if defined(__SSE2__) && !defined(__AVX__)
// The x86-64 baseline: 4 or 8 doubles, 8 floats (and their mask lanes) are held as SSE2 registers
// of 16 bytes, each operator applied to the halves. As GCC's vector types of 32 or 64 bytes a core
// without AVX computes their comparisons, selects and shuffles a lane at a time through the stack
// (comisd, seta, a store, and a wide load that waits on the narrow stores: the box pair's test
// took 4 times its AVX-512 build's time); the halves compute the same IEEE operations lane by lane
#define RTP_SIMD_SPLIT 1
template <typename T, std::size_t N>
struct Split {
  static constexpr std::size_t kHalfLanes = 16 / sizeof(T);
  static_assert(N % kHalfLanes == 0);
  static constexpr std::size_t kHalves = N / kHalfLanes;
  using Half [[gnu::vector_size(16)]] = T;
  using MaskType = Split<LaneInt<T>, N>;
  Half h[kHalves];
  Split() = default;  // lanes undefined, as a scalar's; Split{} is all zero
  constexpr Split(T x) {  // every lane x, so that scalars mix with packs
    [&]<std::size_t... J>(std::index_sequence<J...>) {
      for (Half& half : h) half = Half{((void)J, x)...};
    }(std::make_index_sequence<kHalfLanes>{});
  }
  template <typename... A>
    requires(sizeof...(A) == N)
  constexpr Split(A... a) {
    const T lanes[N] = {T(a)...};
    [&]<std::size_t... J>(std::index_sequence<J...>) {
      for (std::size_t k = 0; k < kHalves; ++k) h[k] = Half{lanes[kHalfLanes * k + J]...};
    }(std::make_index_sequence<kHalfLanes>{});
  }
  T operator[](std::size_t i) const { return h[i / kHalfLanes][i % kHalfLanes]; }
  // (GCC's vector types alias their lane type)
  T& operator[](std::size_t i) { return reinterpret_cast<T*>(h)[i]; }
  template <typename R, typename F>
  [[gnu::always_inline]] static R each(const Split& a, const Split& b, F f) {
    R r;
    for (std::size_t k = 0; k < kHalves; ++k) r.h[k] = f(a.h[k], b.h[k]);
    return r;
  }
  [[gnu::always_inline]]
  friend Split operator+(Split a, Split b) { return each<Split>(a, b, std::plus<>()); }
  [[gnu::always_inline]]
  friend Split operator-(Split a, Split b) { return each<Split>(a, b, std::minus<>()); }
  [[gnu::always_inline]]
  friend Split operator*(Split a, Split b) { return each<Split>(a, b, std::multiplies<>()); }
  [[gnu::always_inline]]
  friend Split operator/(Split a, Split b) { return each<Split>(a, b, std::divides<>()); }
  [[gnu::always_inline]] friend Split operator-(Split a) {
    return each<Split>(a, a, [](Half x, Half) { return -x; });
  }
  [[gnu::always_inline]]
  friend Split operator&(Split a, Split b) { return each<Split>(a, b, std::bit_and<>()); }
  [[gnu::always_inline]]
  friend Split operator|(Split a, Split b) { return each<Split>(a, b, std::bit_or<>()); }
  [[gnu::always_inline]]
  friend Split operator^(Split a, Split b) { return each<Split>(a, b, std::bit_xor<>()); }
  [[gnu::always_inline]] friend Split operator~(Split a) {
    return each<Split>(a, a, [](Half x, Half) { return ~x; });
  }
  [[gnu::always_inline]] Split& operator+=(Split b) { return *this = *this + b; }
  [[gnu::always_inline]] Split& operator-=(Split b) { return *this = *this - b; }
  [[gnu::always_inline]] Split& operator*=(Split b) { return *this = *this * b; }
  [[gnu::always_inline]] Split& operator|=(Split b) { return *this = *this | b; }
  [[gnu::always_inline]] Split& operator&=(Split b) { return *this = *this & b; }
  [[gnu::always_inline]]
  friend MaskType operator<(Split a, Split b) { return each<MaskType>(a, b, std::less<>()); }
  [[gnu::always_inline]]
  friend MaskType operator<=(Split a, Split b) { return each<MaskType>(a, b, std::less_equal<>()); }
  [[gnu::always_inline]]
  friend MaskType operator>(Split a, Split b) { return each<MaskType>(a, b, std::greater<>()); }
  [[gnu::always_inline]] friend MaskType operator>=(Split a, Split b) {
    return each<MaskType>(a, b, std::greater_equal<>());
  }
  [[gnu::always_inline]]
  friend MaskType operator==(Split a, Split b) { return each<MaskType>(a, b, std::equal_to<>()); }
  [[gnu::always_inline]] friend MaskType operator!=(Split a, Split b) {
    return each<MaskType>(a, b, std::not_equal_to<>());
  }
};
// (every pack wider than an SSE2 register)
template <typename T, std::size_t N>
  requires(N * sizeof(T) > 16)
struct VectorOf<T, N> {
  using type = Split<T, N>;
};
template <typename V>
inline constexpr bool kSplit = false;
template <typename T, std::size_t N>
inline constexpr bool kSplit<Split<T, N>> = true;
#else
template <typename V>
inline constexpr bool kSplit = false;
#endif
template <typename T, std::size_t N>
using Pack = typename VectorOf<T, N>::type;
template <typename T, std::size_t N>
using Mask = typename VectorOf<LaneInt<T>, N>::type;  // −1 (all bits) where true, 0 where false
#else
// the scalar fallback: N lanes in an array, each operator a loop over them
template <typename T, std::size_t N>
struct Mask {
  using Int = LaneInt<T>;
  std::array<Int, N> v;  // −1 (all bits) where true, 0 where false
  Mask() = default;
  template <typename... B>
    requires(sizeof...(B) == N)
  constexpr Mask(B... b) : v{Int(b)...} {}
  Int operator[](std::size_t i) const { return v[i]; }
  Int& operator[](std::size_t i) { return v[i]; }
  template <typename F>
  static Mask each(const Mask& a, const Mask& b, F f) {
    Mask r;
    for (std::size_t i = 0; i < N; ++i) r.v[i] = Int(f(a.v[i], b.v[i]));
    return r;
  }
  friend Mask operator&(Mask a, Mask b) { return each(a, b, std::bit_and<>()); }
  friend Mask operator|(Mask a, Mask b) { return each(a, b, std::bit_or<>()); }
  friend Mask operator^(Mask a, Mask b) { return each(a, b, std::bit_xor<>()); }
  friend Mask operator~(Mask a) {
    return each(a, a, [](Int x, Int) { return ~x; });
  }
  Mask& operator|=(Mask b) { return *this = *this | b; }
  Mask& operator&=(Mask b) { return *this = *this & b; }
};

template <typename T, std::size_t N>
struct Pack {
  using MaskType = Mask<T, N>;
  std::array<T, N> v;
  Pack() = default;                         // lanes undefined, as a scalar's; Pack{} is all zero
  constexpr Pack(T x) : v{} { v.fill(x); }  // every lane x, so that scalars mix with packs
  template <typename... A>
    requires(sizeof...(A) == N && N > 1)
  constexpr Pack(A... a) : v{T(a)...} {}
  T operator[](std::size_t i) const { return v[i]; }
  T& operator[](std::size_t i) { return v[i]; }
  template <typename R, typename F>
  static R each(const Pack& a, const Pack& b, F f) {
    R r;
    for (std::size_t i = 0; i < N; ++i) {
      if constexpr (std::is_same_v<R, MaskType>)
        r.v[i] = f(a.v[i], b.v[i]) ? -1 : 0;
      else
        r.v[i] = f(a.v[i], b.v[i]);
    }
    return r;
  }
  friend Pack operator+(Pack a, Pack b) { return each<Pack>(a, b, std::plus<>()); }
  friend Pack operator-(Pack a, Pack b) { return each<Pack>(a, b, std::minus<>()); }
  friend Pack operator*(Pack a, Pack b) { return each<Pack>(a, b, std::multiplies<>()); }
  friend Pack operator/(Pack a, Pack b) { return each<Pack>(a, b, std::divides<>()); }
  friend Pack operator-(Pack a) {
    return each<Pack>(a, a, [](T x, T) { return -x; });
  }
  friend MaskType operator<(Pack a, Pack b) { return each<MaskType>(a, b, std::less<>()); }
  friend MaskType operator<=(Pack a, Pack b) { return each<MaskType>(a, b, std::less_equal<>()); }
  friend MaskType operator>(Pack a, Pack b) { return each<MaskType>(a, b, std::greater<>()); }
  friend MaskType operator>=(Pack a, Pack b) {
    return each<MaskType>(a, b, std::greater_equal<>());
  }
  friend MaskType operator==(Pack a, Pack b) { return each<MaskType>(a, b, std::equal_to<>()); }
  friend MaskType operator!=(Pack a, Pack b) { return each<MaskType>(a, b, std::not_equal_to<>()); }
};
#endif

// a pack's lane type, lane count and mask type
template <typename V>
using LaneOf = std::remove_cvref_t<decltype(std::declval<V&>()[0])>;
template <typename V>
inline constexpr std::size_t kLanesOf = sizeof(V) / sizeof(LaneOf<V>);
template <typename V>
using MaskOf = decltype(std::declval<V>() < std::declval<V>());

// each lane converted to another lane type of the same count (float ↔ double, rounded to
// nearest as a scalar conversion is)
template <typename To, typename From>
To convert(const From& from) {
#ifdef RTP_SIMD_VECTORS
#ifdef RTP_SIMD_SPLIT
  // four floats to four doubles and back, a half at a time (cvtps2pd rounds nothing; cvtpd2ps
  // rounds to nearest, as a scalar conversion does)
  if constexpr (std::is_same_v<From, Pack<float, 4>> && std::is_same_v<To, Split<double, 4>>) {
    To to;
    to.h[0] = _mm_cvtps_pd(from);
    to.h[1] = _mm_cvtps_pd(_mm_movehl_ps(from, from));
    return to;
  }
  if constexpr (std::is_same_v<From, Split<double, 4>> && std::is_same_v<To, Pack<float, 4>>)
    return _mm_movelh_ps(_mm_cvtpd_ps(from.h[0]), _mm_cvtpd_ps(from.h[1]));
#endif
  if constexpr (kSplit<To> || kSplit<From>) {
    To to;
    for (std::size_t i = 0; i < kLanesOf<To>; ++i) to[i] = LaneOf<To>(from[i]);
    return to;
  } else {
    return __builtin_convertvector(from, To);
  }
#else
  To to;
  for (std::size_t i = 0; i < kLanesOf<To>; ++i) to[i] = LaneOf<To>(from[i]);
  return to;
#endif
}

// ---- the lane types ----

using Double4 = Pack<double, 4>;
using Mask4 = Mask<double, 4>;
using Double8 = Pack<double, 8>;
using Mask8 = Mask<double, 8>;
// floats in the widest register the build targets (the broad phase's sweep; the lane count
// changes no result, only how many boxes one comparison covers)
#if defined(RTP_SIMD_VECTORS) && defined(__AVX512F__)
inline constexpr std::size_t kNativeFloats = 16;
#elif defined(RTP_SIMD_VECTORS) && defined(__AVX__)
inline constexpr std::size_t kNativeFloats = 8;
#else
inline constexpr std::size_t kNativeFloats = 4;
#endif

// ---- operations on packs and masks ----

// every lane x
template <typename V>
constexpr V splat(LaneOf<V> x) {
  return [&]<std::size_t... I>(std::index_sequence<I...>) {
    return V{((void)I, x)...};
  }(std::make_index_sequence<kLanesOf<V>>{});
}

// the lanes from p (any alignment)
template <typename V>
V load(const LaneOf<V>* p) {
  V x;
  std::memcpy(&x, p, sizeof x);
  return x;
}
// the lanes to p (any alignment)
template <typename V>
void store(LaneOf<V>* p, const V& x) {
  std::memcpy(p, &x, sizeof x);
}
inline Double4 load4(const double* p) { return load<Double4>(p); }
inline Double8 load8(const double* p) { return load<Double8>(p); }

// a where m is set, b elsewhere
template <typename M, typename V>
[[gnu::always_inline]] inline V select(M m, V a, V b) {
#ifdef RTP_SIMD_VECTORS
  if constexpr (kSplit<V>) {
    V r;
    for (std::size_t k = 0; k < V::kHalves; ++k) r.h[k] = m.h[k] ? a.h[k] : b.h[k];
    return r;
  } else {
    return m ? a : b;
  }
#else
  V r;
  for (std::size_t i = 0; i < kLanesOf<V>; ++i) r[i] = m[i] ? a[i] : b[i];
  return r;
#endif
}

// the lanes' bits reinterpreted: a pack as its mask type and back
template <typename To, typename From>
[[gnu::always_inline]] inline To bits_as(From x) {
  static_assert(sizeof(To) == sizeof(From));
#ifdef RTP_SIMD_VECTORS
  if constexpr (kSplit<To>) {
    To r;
    for (std::size_t k = 0; k < To::kHalves; ++k)
      r.h[k] = reinterpret_cast<typename To::Half>(x.h[k]);
    return r;
  } else {
    return reinterpret_cast<To>(x);
  }
#else
  To r;
  std::memcpy(&r, &x, sizeof r);
  return r;
#endif
}

// |x| by clearing the sign bits: no compare and select
template <typename V>
[[gnu::always_inline]] inline V abs(V x) {
  using M = MaskOf<V>;
  const M magnitude = splat<M>(std::numeric_limits<LaneOf<M>>::max());
  return bits_as<V>(bits_as<M>(x) & magnitude);
}

// −x where m is set, by the sign bit (a compiler branches on a scalar condition's ?:)
template <typename V>
[[gnu::always_inline]] inline V flip_where(V x, MaskOf<V> m) {
  using M = MaskOf<V>;
  const M sign = splat<M>(std::numeric_limits<LaneOf<M>>::min());
  return bits_as<V>(bits_as<M>(x) ^ (m & sign));
}

// the lane-wise least and largest: a < b ? a : b and a > b ? a : b, NaNs and zeros included, by
// the one instruction that computes exactly that where there is one (docs/narrowphase.md, code
// generation)
template <bool Least, typename V>
[[gnu::always_inline]] inline V extreme(V a, V b) {
#if defined(RTP_SIMD_VECTORS) && defined(__AVX__)
  if constexpr (std::is_same_v<V, Double4> && Least) return __builtin_ia32_minpd256(a, b);
  if constexpr (std::is_same_v<V, Double4> && !Least) return __builtin_ia32_maxpd256(a, b);
#endif
#ifdef RTP_SIMD_SPLIT
  // (minpd and maxpd compute a < b ? a : b and a > b ? a : b, as the select does)
  if constexpr (kSplit<V> && std::is_same_v<LaneOf<V>, double>) {
    V r;
    for (std::size_t k = 0; k < V::kHalves; ++k)
      r.h[k] = Least ? _mm_min_pd(a.h[k], b.h[k]) : _mm_max_pd(a.h[k], b.h[k]);
    return r;
  }
#endif
  return select(Least ? a < b : a > b, a, b);
}
template <typename V>
[[gnu::always_inline]] inline V min(V a, V b) {
  return extreme<true>(a, b);
}
template <typename V>
[[gnu::always_inline]] inline V max(V a, V b) {
  return extreme<false>(a, b);
}

// the lane-wise square root, correctly rounded (the instruction where the build has one for the
// pack, else lane by lane)
template <typename V>
V sqrt(V x) {
#if defined(RTP_SIMD_VECTORS) && defined(__AVX512F__)
  if constexpr (std::is_same_v<V, Pack<float, 16>>) return _mm512_maskz_sqrt_ps(0xFFFF, x);
#endif
#if defined(RTP_SIMD_VECTORS) && defined(__AVX__)
  if constexpr (std::is_same_v<V, Pack<float, 8>>) return _mm256_sqrt_ps(x);
#endif
#if defined(RTP_SIMD_VECTORS) && defined(__SSE__)
  if constexpr (std::is_same_v<V, Pack<float, 4>>) return _mm_sqrt_ps(x);
#endif
  V r = x;
  for (std::size_t i = 0; i < kLanesOf<V>; ++i) r[i] = std::sqrt(x[i]);
  return r;
}

// lane i is base[index[i]]: the gather instruction where the build has one for the pack, else
// lane by lane (the same loads either way)
template <typename V>
V gather(const LaneOf<V>* base, MaskOf<V> index) {
#if defined(RTP_SIMD_VECTORS) && defined(__AVX512F__)
  if constexpr (std::is_same_v<V, Pack<float, 16>>)
    return _mm512_mask_i32gather_ps(_mm512_setzero_ps(), 0xFFFF, (__m512i)index, base, 4);
#endif
#if defined(RTP_SIMD_VECTORS) && defined(__AVX2__)
  if constexpr (std::is_same_v<V, Pack<float, 8>>)
    return _mm256_i32gather_ps(base, (__m256i)index, 4);
#endif
  V r{};
  for (std::size_t i = 0; i < kLanesOf<V>; ++i) r[i] = base[index[i]];
  return r;
}

// base[index[i]] = value[i] where lane i of `where` is set: the scatter instruction where the
// build has one for the pack, else lane by lane (the same stores either way; two set lanes with
// one index store in lane order)
template <typename V>
void scatter(LaneOf<V>* base, MaskOf<V> index, V value, MaskOf<V> where) {
#if defined(RTP_SIMD_VECTORS) && defined(__AVX512F__)
  if constexpr (std::is_same_v<V, Pack<float, 16>>) {
    const __mmask16 k = _mm512_cmpneq_epi32_mask((__m512i)where, _mm512_setzero_si512());
    _mm512_mask_i32scatter_ps(base, k, (__m512i)index, value, 4);
    return;
  }
#endif
  for (std::size_t i = 0; i < kLanesOf<V>; ++i)
    if (where[i]) base[index[i]] = value[i];
}

// lanes rearranged: lane i of the result is lane I_i of x
template <std::size_t... I, typename V>
[[gnu::always_inline]] inline V shuffle(V x) {
  static_assert(sizeof...(I) == kLanesOf<V>);
#ifdef RTP_SIMD_VECTORS
  if constexpr (kSplit<V>)
    return shuffle<I...>(x, x);
  else
    return __builtin_shuffle(x, MaskOf<V>{I...});
#else
  return V{x[I]...};
#endif
}
// lanes from two packs: I < N picks lane I of x, I ≥ N lane I − N of y
template <std::size_t... I, typename V>
[[gnu::always_inline]] inline V shuffle(V x, V y) {
  constexpr std::size_t N = kLanesOf<V>;
  static_assert(sizeof...(I) == N);
#ifdef RTP_SIMD_VECTORS
  if constexpr (kSplit<V> && sizeof(LaneOf<V>) != 8) {
    return V{(I < N ? x[I % N] : y[I % N])...};
  } else if constexpr (kSplit<V>) {
    // each half of the result from the two halves that hold its lanes (shufpd)
    using Half = typename V::Half;
    constexpr std::size_t lanes[N] = {I...};
    V r;
    [&]<std::size_t... K>(std::index_sequence<K...>) {
      auto half = [&](std::size_t lane) -> Half {
        return lane < N ? x.h[lane / 2] : y.h[(lane - N) / 2];
      };
      ((r.h[K] = reinterpret_cast<Half>(_mm_shuffle_pd(
            reinterpret_cast<__m128d>(half(lanes[2 * K])),
            reinterpret_cast<__m128d>(half(lanes[2 * K + 1])),
            int(lanes[2 * K] % 2 | (lanes[2 * K + 1] % 2) << 1)))), ...);
    }(std::make_index_sequence<V::kHalves>{});
    return r;
  } else {
    return __builtin_shuffle(x, y, MaskOf<V>{I...});
  }
#else
  return V{(I < N ? x[I % N] : y[I % N])...};
#endif
}

// the largest lane
template <typename V>
LaneOf<V> largest_lane(V x) {
  if constexpr (kLanesOf<V> == 4) {
    return std::max(std::max(x[0], x[1]), std::max(x[2], x[3]));
  } else {
    LaneOf<V> largest = x[0];
    for (std::size_t i = 1; i < kLanesOf<V>; ++i) largest = std::max(largest, x[i]);
    return largest;
  }
}

// asks for the cache lines of [data, data + bytes) ahead of their use, for a loop that streams
// records too large for L2: a hint only, with the same results without it (and on a build without
// vectors, where it is the compiler's portable builtin all the same)
inline void prefetch(const void* data, std::size_t bytes) {
  const char* first = static_cast<const char*>(data);
  for (std::size_t offset = 0; offset < bytes; offset += 64) __builtin_prefetch(first + offset);
}

// bit i set where lane i is: by the instruction that gathers the sign bits where the build has
// one, not lane by lane
template <typename M>
[[gnu::always_inline]] inline unsigned lane_bits(M m) {
  constexpr std::size_t N = kLanesOf<M>, width = sizeof(LaneOf<M>);
#if defined(RTP_SIMD_VECTORS) && defined(__AVX__)
  if constexpr (width == 8 && N == 4)
    return unsigned(__builtin_ia32_movmskpd256(bits_as<Double4>(m)));
  if constexpr (width == 4 && N == 8)
    return unsigned(_mm256_movemask_ps(bits_as<Pack<float, 8>>(m)));
#endif
#if defined(RTP_SIMD_VECTORS) && defined(__SSE__)
  if constexpr (width == 4 && N == 4) return unsigned(_mm_movemask_ps(bits_as<Pack<float, 4>>(m)));
#endif
#ifdef RTP_SIMD_SPLIT
  if constexpr (kSplit<M> && width == 8) {
    unsigned bits = 0;
    for (std::size_t k = 0; k < M::kHalves; ++k)
      bits |= unsigned(_mm_movemask_pd(reinterpret_cast<__m128d>(m.h[k]))) << (2 * k);
    return bits;
  }
  if constexpr (kSplit<M> && width == 4) {
    unsigned bits = 0;
    for (std::size_t k = 0; k < M::kHalves; ++k)
      bits |= unsigned(_mm_movemask_ps(reinterpret_cast<__m128>(m.h[k]))) << (4 * k);
    return bits;
  }
#endif
#if defined(RTP_SIMD_VECTORS) && defined(__AVX512F__)
  // the sign bits, by one compare into a mask register (a loop over the lanes extracts each)
  if constexpr (width == 4 && N == 16)
    return unsigned(_mm512_cmplt_epi32_mask((__m512i)m, _mm512_setzero_si512()));
  if constexpr (width == 8 && N == 8)
    return unsigned(_mm512_cmplt_epi64_mask((__m512i)m, _mm512_setzero_si512()));
#endif
  if constexpr (width == 8 && N == 8) {
    // two halves of four
    Mask4 half[2];
    std::memcpy(half, &m, sizeof half);
    return lane_bits(half[0]) | lane_bits(half[1]) << 4;
  } else {
    unsigned bits = 0;
    for (std::size_t i = 0; i < N; ++i) bits |= unsigned(m[i] & (LaneOf<M>(1) << i));
    return bits;
  }
}
template <typename M>
int lane_count(M m) {
  return std::popcount(lane_bits(m));
}
template <typename M>
bool any_of(M m) {
  return lane_bits(m) != 0;
}
template <typename M>
bool all_of(M m) {
  return lane_bits(m) == (1u << kLanesOf<M>)-1u;
}

// Records of floats, one a lane: the first 8 floats of the record at base + offset[i] as lane i of
// rows[0..7] (rows[k][i] = base[offset[i] + k]), and the first 6 or all 8 written back where a
// lane is set.
// With AVX-512 (16 lanes), each record's 32 bytes are loaded whole and transposed, and written
// back by masked 32-byte stores: a gather or scatter instruction costs one load or store a lane,
// and a pass over a block's bodies would take six of each a body. With AVX2 (8 lanes), which has
// no scatter instruction, each record is loaded as two 16-byte halves, transposed 8 × 8, and
// written back by 16-byte stores (and an 8-byte one for six floats). With SSE (4 lanes), each
// record is loaded as two 16-byte halves and each half's four records transposed 4 × 4, and
// written back the same way. Elsewhere a gather or scatter a row. The same floats move either
// way.
// Always inlined: called, the kernels pass their lanes through memory (measured: the solve's ns
// per point and pass 7.80 against 7.28 at base 20, minima of ten alternating runs).
#if defined(RTP_SIMD_VECTORS) && defined(__AVX512F__)
// rows[i] holding records i (low half) and i + 8 (high half) becomes rows[k] holding float k of
// every record, lane i; the same applied again gives the records back
[[gnu::always_inline]] inline void transpose_records16(__m512 (&rows)[8]) {
  __m512 t[8], u[8];
  for (int i = 0; i < 8; i += 2) {
    t[i] = _mm512_unpacklo_ps(rows[i], rows[i + 1]);
    t[i + 1] = _mm512_unpackhi_ps(rows[i], rows[i + 1]);
  }
  for (int i = 0; i < 8; i += 4) {
    u[i] = _mm512_shuffle_ps(t[i], t[i + 2], 0x44);
    u[i + 1] = _mm512_shuffle_ps(t[i], t[i + 2], 0xEE);
    u[i + 2] = _mm512_shuffle_ps(t[i + 1], t[i + 3], 0x44);
    u[i + 3] = _mm512_shuffle_ps(t[i + 1], t[i + 3], 0xEE);
  }
  const __m512i low = _mm512_setr_epi32(0, 1, 2, 3, 16, 17, 18, 19, 8, 9, 10, 11, 24, 25, 26, 27);
  const __m512i high =
      _mm512_setr_epi32(4, 5, 6, 7, 20, 21, 22, 23, 12, 13, 14, 15, 28, 29, 30, 31);
  for (int k = 0; k < 4; ++k) {
    rows[k] = _mm512_permutex2var_ps(u[k], low, u[k + 4]);
    rows[k + 4] = _mm512_permutex2var_ps(u[k], high, u[k + 4]);
  }
}
#endif

#if defined(RTP_SIMD_VECTORS) && defined(__AVX__)
// four rows transposed 4 × 4 within each 128-bit half (two rounds of shuffles); its own inverse.
// Rows holding floats f..f+3 of records i (low half) and i + 4 (high half), i < 4, become rows
// holding float f + k of every record (lane i); and back
[[gnu::always_inline]] inline void transpose_quads8(const __m256* in, __m256 (&out)[4]) {
  const __m256 t0 = _mm256_unpacklo_ps(in[0], in[1]), t1 = _mm256_unpackhi_ps(in[0], in[1]);
  const __m256 t2 = _mm256_unpacklo_ps(in[2], in[3]), t3 = _mm256_unpackhi_ps(in[2], in[3]);
  out[0] = _mm256_shuffle_ps(t0, t2, 0x44), out[1] = _mm256_shuffle_ps(t0, t2, 0xEE);
  out[2] = _mm256_shuffle_ps(t1, t3, 0x44), out[3] = _mm256_shuffle_ps(t1, t3, 0xEE);
}
#endif

template <typename V>
[[gnu::always_inline]] inline void gather_records(const LaneOf<V>* base, MaskOf<V> offset,
                                                  V (&rows)[8]) {
  static_assert(std::is_same_v<LaneOf<V>, float>);
#if defined(RTP_SIMD_VECTORS) && defined(__AVX512F__)
  if constexpr (std::is_same_v<V, Pack<float, 16>>) {
    alignas(64) std::int32_t at[16];
    std::memcpy(at, &offset, sizeof at);
    __m512 r[8];
    // (the 64-bit insert and extract are AVX-512F's own; the 32-bit ones need DQ)
    for (int i = 0; i < 8; ++i)
      r[i] = _mm512_castpd_ps(_mm512_insertf64x4(
          _mm512_castpd256_pd512(_mm256_castps_pd(_mm256_loadu_ps(base + at[i]))),
          _mm256_castps_pd(_mm256_loadu_ps(base + at[i + 8])), 1));
    transpose_records16(r);
    for (int k = 0; k < 8; ++k) rows[k] = r[k];
    return;
  }
#endif
#if defined(RTP_SIMD_VECTORS) && defined(__AVX__)
  if constexpr (std::is_same_v<V, Pack<float, 8>>) {
    alignas(32) std::int32_t at[8];
    std::memcpy(at, &offset, sizeof at);
    // floats 4h–4h+3 of records i and i + 4 in r[h][i], the halves placed by the loads
    __m256 r[2][4], t[4];
    for (int h = 0; h < 2; ++h) {
      for (int i = 0; i < 4; ++i)
        r[h][i] = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(base + at[i] + 4 * h)),
                                       _mm_loadu_ps(base + at[i + 4] + 4 * h), 1);
      transpose_quads8(r[h], t);
      for (int k = 0; k < 4; ++k) rows[4 * h + k] = t[k];
    }
    return;
  }
#endif
#if defined(RTP_SIMD_VECTORS) && defined(__SSE__)
  if constexpr (std::is_same_v<V, Pack<float, 4>>) {
    alignas(16) std::int32_t at[4];
    std::memcpy(at, &offset, sizeof at);
    for (int h = 0; h < 2; ++h) {
      __m128 q0 = _mm_loadu_ps(base + at[0] + 4 * h), q1 = _mm_loadu_ps(base + at[1] + 4 * h);
      __m128 q2 = _mm_loadu_ps(base + at[2] + 4 * h), q3 = _mm_loadu_ps(base + at[3] + 4 * h);
      _MM_TRANSPOSE4_PS(q0, q1, q2, q3);
      rows[4 * h] = q0, rows[4 * h + 1] = q1, rows[4 * h + 2] = q2, rows[4 * h + 3] = q3;
    }
    return;
  }
#endif
#ifdef RTP_SIMD_SPLIT
  if constexpr (kSplit<V>) {
    // a half's four records at a time, as four lanes are (above)
    using Q = Pack<float, 4>;
    for (std::size_t k = 0; k < V::kHalves; ++k) {
      Q half_rows[8];
      gather_records<Q>(base, offset.h[k], half_rows);
      for (int r = 0; r < 8; ++r) rows[r].h[k] = half_rows[r];
    }
    return;
  }
#endif
  for (int k = 0; k < 8; ++k) rows[k] = gather<V>(base + k, offset);
}

template <typename V, std::size_t R>
[[gnu::always_inline]] inline void scatter_records(LaneOf<V>* base, MaskOf<V> offset,
                                                   const V (&rows)[R], MaskOf<V> where) {
  static_assert(std::is_same_v<LaneOf<V>, float>);
  static_assert(R == 6 || R == 8, "a record's first six floats, or all eight");
#if defined(RTP_SIMD_VECTORS) && defined(__AVX512F__) && defined(__AVX512VL__)
  if constexpr (std::is_same_v<V, Pack<float, 16>>) {
    alignas(64) std::int32_t at[16];
    std::memcpy(at, &offset, sizeof at);
    const unsigned set = lane_bits(where);
    constexpr __mmask8 kFloats = R == 8 ? 0xFF : 0x3F;
    __m512 r[8];
    for (std::size_t k = 0; k < R; ++k) r[k] = rows[k];
    for (std::size_t k = R; k < 8; ++k) r[k] = _mm512_setzero_ps();
    transpose_records16(r);
    for (int i = 0; i < 8; ++i) {
      // the record's first R floats, and only where the lane is set
      if (set >> i & 1u)
        _mm256_mask_storeu_ps(base + at[i], kFloats, _mm512_castps512_ps256(r[i]));
      if (set >> (i + 8) & 1u)
        _mm256_mask_storeu_ps(base + at[i + 8], kFloats,
                              _mm256_castpd_ps(_mm512_extractf64x4_pd(_mm512_castps_pd(r[i]), 1)));
    }
    return;
  }
#endif
#if defined(RTP_SIMD_VECTORS) && defined(__AVX__)
  if constexpr (std::is_same_v<V, Pack<float, 8>>) {
    alignas(32) std::int32_t at[8];
    std::memcpy(at, &offset, sizeof at);
    const unsigned set = lane_bits(where);
    // floats 4h–4h+3 of records i and i + 4 in q[h][i]; with six rows, floats 4 and 5 of
    // records 0, 1 | 4, 5 in p[0], of records 2, 3 | 6, 7 in p[1]
    auto half = [](__m256 x, int h) {
      return h == 0 ? _mm256_castps256_ps128(x) : _mm256_extractf128_ps(x, 1);
    };
    __m256 q[2][4];
    transpose_quads8(rows, q[0]);
    if constexpr (R == 8) {
      transpose_quads8(rows + 4, q[1]);
      for (int h = 0; h < 2; ++h)
        for (int i = 0; i < 4; ++i) {
          const int lane = i + 4 * h;
          if (!(set >> lane & 1u)) continue;
          _mm_storeu_ps(base + at[lane], half(q[0][i], h));
          _mm_storeu_ps(base + at[lane] + 4, half(q[1][i], h));
        }
    } else {
      const __m256 p[2] = {_mm256_unpacklo_ps(rows[4], rows[5]),
                           _mm256_unpackhi_ps(rows[4], rows[5])};
      for (int h = 0; h < 2; ++h)
        for (int i = 0; i < 4; ++i) {
          const int lane = i + 4 * h;
          if (!(set >> lane & 1u)) continue;
          const __m128 last = half(p[i / 2], h);
          _mm_storeu_ps(base + at[lane], half(q[0][i], h));
          if (i % 2 == 0)
            _mm_storel_pi(reinterpret_cast<__m64*>(base + at[lane] + 4), last);
          else
            _mm_storeh_pi(reinterpret_cast<__m64*>(base + at[lane] + 4), last);
        }
    }
    return;
  }
#endif
#if defined(RTP_SIMD_VECTORS) && defined(__SSE__)
  if constexpr (std::is_same_v<V, Pack<float, 4>>) {
    alignas(16) std::int32_t at[4];
    std::memcpy(at, &offset, sizeof at);
    const unsigned set = lane_bits(where);
    __m128 q[4] = {rows[0], rows[1], rows[2], rows[3]};
    _MM_TRANSPOSE4_PS(q[0], q[1], q[2], q[3]);
    __m128 p[4] = {rows[4], rows[5], _mm_setzero_ps(), _mm_setzero_ps()};
    if constexpr (R == 8) p[2] = rows[6], p[3] = rows[7];
    _MM_TRANSPOSE4_PS(p[0], p[1], p[2], p[3]);
    for (int i = 0; i < 4; ++i) {
      if (!(set >> i & 1u)) continue;
      _mm_storeu_ps(base + at[i], q[i]);
      if constexpr (R == 8)
        _mm_storeu_ps(base + at[i] + 4, p[i]);
      else
        _mm_storel_pi(reinterpret_cast<__m64*>(base + at[i] + 4), p[i]);
    }
    return;
  }
#endif
#ifdef RTP_SIMD_SPLIT
  if constexpr (kSplit<V>) {
    using Q = Pack<float, 4>;
    for (std::size_t k = 0; k < V::kHalves; ++k) {
      Q half_rows[R];
      for (std::size_t r = 0; r < R; ++r) half_rows[r] = rows[r].h[k];
      scatter_records<Q>(base, offset.h[k], half_rows, where.h[k]);
    }
    return;
  }
#endif
  for (std::size_t k = 0; k < R; ++k) scatter(base + k, offset, rows[k], where);
}

// ---- the broad phase's floats ----

// FloatN and MaskN: kNativeFloats floats and a mask of them, compared by name (at_most, at_least,
// equal) rather than by operator so that with AVX-512 the mask can be a mask register: compares,
// ANDs and the final test then stay there, where a vector mask costs a conversion each way.
#if defined(RTP_SIMD_VECTORS) && defined(__AVX512F__)
using FloatN = __m512;
using MaskN = __mmask16;
inline FloatN load_floats(const float* p) { return _mm512_loadu_ps(p); }
inline FloatN splat_floats(float x) { return _mm512_set1_ps(x); }
inline MaskN at_most(FloatN a, FloatN b) { return _mm512_cmp_ps_mask(a, b, _CMP_LE_OQ); }
inline MaskN at_least(FloatN a, FloatN b) { return _mm512_cmp_ps_mask(a, b, _CMP_GE_OQ); }
inline MaskN equal(FloatN a, FloatN b) { return _mm512_cmp_ps_mask(a, b, _CMP_EQ_OQ); }
// (the zero-masked form under a full mask: GCC bug 105593, below)
inline FloatN max(FloatN a, FloatN b) { return _mm512_maskz_max_ps(0xFFFF, a, b); }
inline unsigned lane_bits(MaskN m) { return m; }
inline bool any_of(MaskN m) { return m != 0; }
inline bool all_of(MaskN m) { return m == 0xFFFF; }
#else
using FloatN = Pack<float, kNativeFloats>;
using MaskN = Mask<float, kNativeFloats>;
inline FloatN load_floats(const float* p) { return load<FloatN>(p); }
inline FloatN splat_floats(float x) { return splat<FloatN>(x); }
inline MaskN at_most(FloatN a, FloatN b) { return a <= b; }
inline MaskN at_least(FloatN a, FloatN b) { return a >= b; }
inline MaskN equal(FloatN a, FloatN b) { return a == b; }
#endif

// ---- 16 floats for the particle kernels ----

#ifdef RTP_SIMD_AVX512_KERNELS
using Mask16 = __mmask16;
struct Float16 {
  __m512 v;
};
#define RTP_F16 RTP_SIMD_TARGET_AVX512 inline
// The unmasked forms of min, max, rsqrt14 and rcp14 fill a register from an "undefined" one, which
// GCC 12 reports as maybe uninitialised at every use (GCC bug 105593); the zero-masked forms under
// a full mask compile to the same instructions.
inline constexpr Mask16 kAll16 = 0xFFFF;
RTP_F16 Float16 splat16(float x) { return {_mm512_set1_ps(x)}; }
RTP_F16 Float16 zero16() { return {_mm512_setzero_ps()}; }
// the lanes of m from p, zero elsewhere; the lanes of m to p
RTP_F16 Float16 load16(Mask16 m, const float* p) { return {_mm512_maskz_loadu_ps(m, p)}; }
RTP_F16 void store16(float* p, Mask16 m, Float16 x) { _mm512_mask_storeu_ps(p, m, x.v); }
RTP_F16 Float16 add(Float16 a, Float16 b) { return {_mm512_add_ps(a.v, b.v)}; }
RTP_F16 Float16 sub(Float16 a, Float16 b) { return {_mm512_sub_ps(a.v, b.v)}; }
RTP_F16 Float16 mul(Float16 a, Float16 b) { return {_mm512_mul_ps(a.v, b.v)}; }
// a b + c, −(a b) + c and a b − c, each rounded once
RTP_F16 Float16 fmadd(Float16 a, Float16 b, Float16 c) { return {_mm512_fmadd_ps(a.v, b.v, c.v)}; }
RTP_F16 Float16 fnmadd(Float16 a, Float16 b, Float16 c) {
  return {_mm512_fnmadd_ps(a.v, b.v, c.v)};
}
RTP_F16 Float16 fmsub(Float16 a, Float16 b, Float16 c) { return {_mm512_fmsub_ps(a.v, b.v, c.v)}; }
RTP_F16 Float16 min(Float16 a, Float16 b) { return {_mm512_maskz_min_ps(kAll16, a.v, b.v)}; }
RTP_F16 Float16 max(Float16 a, Float16 b) { return {_mm512_maskz_max_ps(kAll16, a.v, b.v)}; }
// 1/√x and 1/x within a relative 2⁻¹⁴ (the core's estimates)
RTP_F16 Float16 rsqrt_estimate(Float16 a) { return {_mm512_maskz_rsqrt14_ps(kAll16, a.v)}; }
RTP_F16 Float16 reciprocal_estimate(Float16 a) { return {_mm512_maskz_rcp14_ps(kAll16, a.v)}; }
RTP_F16 Mask16 less(Float16 a, Float16 b) { return _mm512_cmp_ps_mask(a.v, b.v, _CMP_LT_OQ); }
RTP_F16 Mask16 greater(Float16 a, Float16 b) { return _mm512_cmp_ps_mask(a.v, b.v, _CMP_GT_OQ); }
// a where m is set, b elsewhere; a where m is set, 0 elsewhere
RTP_F16 Float16 select(Mask16 m, Float16 a, Float16 b) { return {_mm512_mask_mov_ps(b.v, m, a.v)}; }
RTP_F16 Float16 select_or_zero(Mask16 m, Float16 a) { return {_mm512_maskz_mov_ps(m, a.v)}; }
#undef RTP_F16

// whether the running core has AVX-512F: the particle kernels' run-time dispatch
inline bool core_has_avx512() { return __builtin_cpu_supports("avx512f"); }
#else
using Mask16 = std::uint16_t;
struct Float16 {
  std::array<float, 16> v;
};
inline constexpr Mask16 kAll16 = 0xFFFF;
template <typename F>
Float16 lanewise16(F f) {
  Float16 r;
  for (std::size_t i = 0; i < 16; ++i) r.v[i] = f(i);
  return r;
}
template <typename F>
Mask16 compare16(F f) {
  unsigned bits = 0;
  for (std::size_t i = 0; i < 16; ++i) bits |= unsigned(f(i)) << i;
  return Mask16(bits);
}
inline bool lane(Mask16 m, std::size_t i) { return (m >> i) & 1u; }
inline Float16 splat16(float x) {
  return lanewise16([&](std::size_t) { return x; });
}
inline Float16 zero16() { return splat16(0.0f); }
inline Float16 load16(Mask16 m, const float* p) {
  return lanewise16([&](std::size_t i) { return lane(m, i) ? p[i] : 0.0f; });
}
inline void store16(float* p, Mask16 m, Float16 x) {
  for (std::size_t i = 0; i < 16; ++i)
    if (lane(m, i)) p[i] = x.v[i];
}
inline Float16 add(Float16 a, Float16 b) {
  return lanewise16([&](std::size_t i) { return a.v[i] + b.v[i]; });
}
inline Float16 sub(Float16 a, Float16 b) {
  return lanewise16([&](std::size_t i) { return a.v[i] - b.v[i]; });
}
inline Float16 mul(Float16 a, Float16 b) {
  return lanewise16([&](std::size_t i) { return a.v[i] * b.v[i]; });
}
inline Float16 fmadd(Float16 a, Float16 b, Float16 c) {
  return lanewise16([&](std::size_t i) { return std::fma(a.v[i], b.v[i], c.v[i]); });
}
inline Float16 fnmadd(Float16 a, Float16 b, Float16 c) {
  return lanewise16([&](std::size_t i) { return std::fma(-a.v[i], b.v[i], c.v[i]); });
}
inline Float16 fmsub(Float16 a, Float16 b, Float16 c) {
  return lanewise16([&](std::size_t i) { return std::fma(a.v[i], b.v[i], -c.v[i]); });
}
inline Float16 min(Float16 a, Float16 b) {
  return lanewise16([&](std::size_t i) { return a.v[i] < b.v[i] ? a.v[i] : b.v[i]; });
}
inline Float16 max(Float16 a, Float16 b) {
  return lanewise16([&](std::size_t i) { return a.v[i] > b.v[i] ? a.v[i] : b.v[i]; });
}
// exact where the vector forms estimate (see the top of the file)
inline Float16 rsqrt_estimate(Float16 a) {
  return lanewise16([&](std::size_t i) { return 1.0f / std::sqrt(a.v[i]); });
}
inline Float16 reciprocal_estimate(Float16 a) {
  return lanewise16([&](std::size_t i) { return 1.0f / a.v[i]; });
}
inline Mask16 less(Float16 a, Float16 b) {
  return compare16([&](std::size_t i) { return a.v[i] < b.v[i]; });
}
inline Mask16 greater(Float16 a, Float16 b) {
  return compare16([&](std::size_t i) { return a.v[i] > b.v[i]; });
}
inline Float16 select(Mask16 m, Float16 a, Float16 b) {
  return lanewise16([&](std::size_t i) { return lane(m, i) ? a.v[i] : b.v[i]; });
}
inline Float16 select_or_zero(Mask16 m, Float16 a) { return select(m, a, zero16()); }

inline bool core_has_avx512() { return false; }
#endif

// whether the running core runs code built for x86-64-v4 (AVX-512F, BW, CD, DQ and VL beside
// v3) or x86-64-v3 (AVX2, FMA, BMI1 and 2, F16C, LZCNT, MOVBE): which copy of the contact passes
// the baseline build runs (contact_dispatch.cpp); the core and its system both (GCC's check reads
// whether the system saves the registers too)
#if defined(__x86_64__) && defined(__GNUC__)
inline bool core_runs_x86_64_v4() { return __builtin_cpu_supports("x86-64-v4"); }
inline bool core_runs_x86_64_v3() { return __builtin_cpu_supports("x86-64-v3"); }
#else
inline bool core_runs_x86_64_v4() { return false; }
inline bool core_runs_x86_64_v3() { return false; }
#endif

// the lanes of a 16-lane group starting at j that are below n: all but in a last, partial group
inline Mask16 lanes_below(std::size_t n, std::size_t j) {
  return static_cast<Mask16>(n - j >= 16 ? 0xFFFFu : (1u << (n - j)) - 1u);
}

}  // namespace rtp::simd
