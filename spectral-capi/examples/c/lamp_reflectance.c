/*
 * A renderer's use of fspec.h in plain C11: an LED-like lamp and a tungsten
 * lamp (a 2856 K blackbody) light a red paint. Each spectrum is projected
 * once onto N Fourier coefficients; lighting is the truncated product of
 * coefficients; colour is XYZ, here by each of the four routes, and eight
 * spectra are multiplied at once in the 8-lane layout (coeffs[j*8 + lane]).
 *
 * Build (from the workspace root, after `cargo build --release -p spectral-capi`):
 *   cc -std=c11 -Ispectral-capi/include spectral-capi/examples/c/lamp_reflectance.c \
 *      target/release/libspectral_capi.a -lm -lpthread -ldl -o lamp_reflectance
 */
#include <stdio.h>
#include <stdlib.h>

#include "fspec.h"

/* Coefficients per spectrum. */
#define N 16
#define LED_SAMPLES 9
#define RED_SAMPLES 6
/* CIE illuminant A's colour temperature, K. */
#define TUNGSTEN_K 2856.0

/* An LED-like lamp: a blue peak and a broad phosphor hump. */
static const double LED_NM[LED_SAMPLES] = {380, 430, 450, 470, 500, 560, 600, 680, 780};
static const double LED_VALUES[LED_SAMPLES] = {0.0, 0.2, 1.0, 0.25, 0.3, 0.6, 0.55, 0.2, 0.0};
/* A red paint's reflectance. */
static const double RED_NM[RED_SAMPLES] = {380, 480, 560, 600, 640, 780};
static const double RED_VALUES[RED_SAMPLES] = {0.05, 0.05, 0.08, 0.4, 0.7, 0.75};

/* Every fspec call returns a status; a renderer would report and recover. */
static void check(FspecStatus status, const char *what) {
    if (status != FSPEC_STATUS_OK) {
        fprintf(stderr, "%s failed with status %d\n", what, (int)status);
        exit(1);
    }
}

static void print_xyz(const char *label, const double xyz[3]) {
    printf("%s %.9e %.9e %.9e\n", label, xyz[0], xyz[1], xyz[2]);
}

int main(void) {
    const FspecRange visible = {360.0, 830.0};
    double led[N], red[N], tungsten[N], lit[N], xyz[3];

    check(fspec_project_tabulated(visible, LED_NM, LED_VALUES, LED_SAMPLES, N, led), "LED");
    check(fspec_project_tabulated(visible, RED_NM, RED_VALUES, RED_SAMPLES, N, red), "paint");
    check(fspec_project_blackbody(visible, TUNGSTEN_K, N, tungsten), "blackbody");
    check(fspec_product(led, red, N, lit), "product");

    /* A converter lives in caller memory: ask for its size, allocate, build once. */
    size_t bytes = 0;
    check(fspec_xyz_converter_size(N, &bytes), "converter size");
    void *converter = malloc(bytes);
    if (converter == NULL) {
        return 1;
    }
    check(fspec_xyz_converter_init(converter, bytes, visible, N), "converter");
    const struct {
        const char *label;
        FspecXyzRoute route;
    } routes[] = {
        {"led_red_series", FSPEC_XYZ_ROUTE_SERIES},
        {"led_red_lut", FSPEC_XYZ_ROUTE_LUT},
        {"led_red_zeroth", FSPEC_XYZ_ROUTE_ZEROTH},
        {"led_red_mese", FSPEC_XYZ_ROUTE_MESE},
    };
    for (size_t i = 0; i < sizeof routes / sizeof routes[0]; ++i) {
        check(fspec_xyz_converter_apply(converter, routes[i].route, lit, N, xyz), routes[i].label);
        print_xyz(routes[i].label, xyz);
    }
    free(converter);

    /* In place: the output may alias an input. */
    check(fspec_product(tungsten, red, N, tungsten), "product in place");
    FspecXyzKernel kernel;
    check(fspec_xyz_kernel_init(&kernel, visible, N), "kernel");
    check(fspec_xyz_kernel_apply(&kernel, tungsten, N, xyz), "kernel apply");
    print_xyz("tungsten_red_zeroth", xyz);

    /* Eight ray lanes: lane `lane` carries the LED dimmed to (lane + 1)/8. */
    float lanes_led[N * FSPEC_LANES], lanes_red[N * FSPEC_LANES], lanes_xyz[3 * FSPEC_LANES];
    for (int j = 0; j < N; ++j) {
        for (int lane = 0; lane < FSPEC_LANES; ++lane) {
            lanes_led[j * FSPEC_LANES + lane] = (float)(led[j] * (lane + 1) / FSPEC_LANES);
            lanes_red[j * FSPEC_LANES + lane] = (float)red[j];
        }
    }
    check(fspec_product_x8(lanes_led, lanes_red, N, lanes_led), "8-lane product");
    check(fspec_xyz_kernel_apply_x8(&kernel, lanes_led, N, lanes_xyz), "8-lane XYZ");
    printf("lanes_y");
    for (int lane = 0; lane < FSPEC_LANES; ++lane) {
        printf(" %.9e", (double)lanes_xyz[1 * FSPEC_LANES + lane]);
    }
    printf("\n");
    return 0;
}
