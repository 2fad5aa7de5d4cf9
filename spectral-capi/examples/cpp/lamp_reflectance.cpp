// A renderer's use of fspec.h from C++17: the scene of the C example (an
// LED-like lamp and a 2856 K blackbody on a red paint, N = 16), with the
// status codes turned into exceptions and the caller-allocated converter
// owned by a std::vector.
//
// Build (from the workspace root, after `cargo build --release -p spectral-capi`):
//   c++ -std=c++17 -Ispectral-capi/include spectral-capi/examples/cpp/lamp_reflectance.cpp
//       target/release/libspectral_capi.a -lm -lpthread -ldl -o lamp_reflectance_cpp
// (one command line).
#include <array>
#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "fspec.h"

namespace {

constexpr std::uint32_t kCoeffs = 16;  // coefficients per spectrum
constexpr double kTungstenK = 2856.0;  // CIE illuminant A's colour temperature
constexpr FspecRange kVisible{360.0, 830.0};

using Coeffs = std::array<double, kCoeffs>;
using Xyz = std::array<double, 3>;

// An LED-like lamp (a blue peak and a phosphor hump) and a red paint.
constexpr std::array<double, 9> kLedNm{380, 430, 450, 470, 500, 560, 600, 680, 780};
constexpr std::array<double, 9> kLedValues{0.0, 0.2, 1.0, 0.25, 0.3, 0.6, 0.55, 0.2, 0.0};
constexpr std::array<double, 6> kRedNm{380, 480, 560, 600, 640, 780};
constexpr std::array<double, 6> kRedValues{0.05, 0.05, 0.08, 0.4, 0.7, 0.75};

void check(FspecStatus status, const char* what) {
    if (status != FSPEC_STATUS_OK) {
        throw std::runtime_error(std::string(what) + " failed with status " +
                                 std::to_string(static_cast<int>(status)));
    }
}

template <std::size_t S>
Coeffs project(const std::array<double, S>& nm, const std::array<double, S>& values) {
    Coeffs c{};
    check(fspec_project_tabulated(kVisible, nm.data(), values.data(), S, kCoeffs, c.data()),
          "projection");
    return c;
}

Coeffs operator*(const Coeffs& a, const Coeffs& b) {
    Coeffs h{};
    check(fspec_product(a.data(), b.data(), kCoeffs, h.data()), "product");
    return h;
}

// An XYZ converter in memory the program owns (8-byte aligned: uint64_t).
class XyzConverter {
   public:
    XyzConverter(FspecRange range, std::uint32_t n) : n_(n) {
        std::size_t bytes = 0;
        check(fspec_xyz_converter_size(n, &bytes), "converter size");
        storage_.resize((bytes + sizeof(std::uint64_t) - 1) / sizeof(std::uint64_t));
        check(fspec_xyz_converter_init(storage_.data(), bytes, range, n), "converter");
    }
    Xyz operator()(FspecXyzRoute route, const Coeffs& c) const {
        Xyz xyz{};
        check(fspec_xyz_converter_apply(storage_.data(), route, c.data(), n_, xyz.data()),
              "XYZ");
        return xyz;
    }

   private:
    std::uint32_t n_;
    std::vector<std::uint64_t> storage_;
};

void print_xyz(const char* label, const Xyz& xyz) {
    std::printf("%s %.9e %.9e %.9e\n", label, xyz[0], xyz[1], xyz[2]);
}

}  // namespace

int main() {
    try {
        const Coeffs led = project(kLedNm, kLedValues);
        const Coeffs red = project(kRedNm, kRedValues);
        Coeffs tungsten{};
        check(fspec_project_blackbody(kVisible, kTungstenK, kCoeffs, tungsten.data()),
              "blackbody");

        const XyzConverter to_xyz(kVisible, kCoeffs);
        const Coeffs lit = led * red;
        print_xyz("led_red_series", to_xyz(FSPEC_XYZ_ROUTE_SERIES, lit));
        print_xyz("led_red_lut", to_xyz(FSPEC_XYZ_ROUTE_LUT, lit));
        print_xyz("led_red_zeroth", to_xyz(FSPEC_XYZ_ROUTE_ZEROTH, lit));
        print_xyz("led_red_mese", to_xyz(FSPEC_XYZ_ROUTE_MESE, lit));
        print_xyz("tungsten_red_zeroth", to_xyz(FSPEC_XYZ_ROUTE_ZEROTH, tungsten * red));

        // Eight ray lanes, coefficient-major: lane `lane` carries the LED dimmed
        // to (lane + 1)/8.
        constexpr std::size_t kLanes = FSPEC_LANES;
        std::array<float, kCoeffs * kLanes> lanes_led{}, lanes_red{}, lanes_lit{};
        for (std::size_t j = 0; j < kCoeffs; ++j) {
            for (std::size_t lane = 0; lane < kLanes; ++lane) {
                lanes_led[j * kLanes + lane] = static_cast<float>(led[j] * (lane + 1) / kLanes);
                lanes_red[j * kLanes + lane] = static_cast<float>(red[j]);
            }
        }
        check(fspec_product_x8(lanes_led.data(), lanes_red.data(), kCoeffs, lanes_lit.data()),
              "8-lane product");
        FspecXyzKernel kernel{};
        check(fspec_xyz_kernel_init(&kernel, kVisible, kCoeffs), "kernel");
        std::array<float, 3 * kLanes> lanes_xyz{};
        check(fspec_xyz_kernel_apply_x8(&kernel, lanes_lit.data(), kCoeffs, lanes_xyz.data()),
              "8-lane XYZ");
        std::printf("lanes_y");
        for (std::size_t lane = 0; lane < kLanes; ++lane) {
            std::printf(" %.9e", static_cast<double>(lanes_xyz[kLanes + lane]));
        }
        std::printf("\n");
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
    return 0;
}
