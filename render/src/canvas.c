/* Drawing one snapshot off-screen: OSMesa context, particles as instanced anti-aliased discs (OpenGL 3.3
 * core), then the overlays (colour bar, time, length scale) composited on the CPU (see surge/render.h). */
#define _POSIX_C_SOURCE 200809L
#define GL_GLEXT_PROTOTYPES
#include "surge/render.h"

#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "png_io.h"

static const double pi = 3.14159265358979323846;
#include "colormaps.h"
#include "text.h"

/* Colours of what is not fluid (sRGB). */
static const uint8_t background_rgb[3] = {255, 255, 255};
static const uint8_t wall_rgb[3] = {150, 150, 150};  /* fixed walls: grey */
static const uint8_t belt_rgb[3] = {205, 110, 40};   /* the moving belt: orange-brown, outside both colour maps */
static const uint8_t boulder_rgb[3] = {95, 80, 70};   /* boulders: dark grey-brown */
static const uint8_t mark_rgb[3] = {235, 235, 235};   /* a boulder's orientation mark: its particles within 25 deg
                                                         of its angle, seen from its centre */
enum { MARK_HALF_ANGLE_DEG = 25 };

/* Boulder colour of particle i: the mark when it lies in the sector of its disc's orientation. */
static const uint8_t *boulder_colour(const surge_snapshot *s, int i, const surge_params *p)
{
    const surge_boulder_state *b = &s->boulders;
    const double period = p->domain.periodic_x ? p->domain.length_m : 0;
    for (int j = 0; j < b->count; j++) {
        double dx = s->x_m[i] - b->x_m[j];
        if (period > 0)
            dx -= period * floor(dx / period + 0.5);
        const double dy = s->y_m[i] - b->y_m[j];
        if (dx * dx + dy * dy > b->radius_m[j] * b->radius_m[j])
            continue;
        const double along = dx * cos(b->angle_rad[j]) + dy * sin(b->angle_rad[j]);
        return along > hypot(dx, dy) * cos(MARK_HALF_ANGLE_DEG * pi / 180.0) ? mark_rgb : boulder_rgb;
    }
    return boulder_rgb;
}
static const uint8_t ink_rgb[3] = {0, 0, 0};

typedef struct instance {
    float x_px, y_px;
    float r, g, b;
} instance;

struct surge_canvas {
    int width, height;
    OSMesaContext context;
    uint8_t *pixels; /* RGBA, top row first (OSMESA_Y_UP = 0) */
    GLuint program, vao, quad_vbo, instance_vbo;
    GLint uniform_viewport, uniform_radius;
    instance *instances;
    int instance_capacity;
    surge_text *text;
    surge_canvas_layout layout;
    double grown_min, grown_max; /* an automatic colour range so far (NaN: none yet); it only grows */
};

static const char *vertex_shader =
    "#version 330 core\n"
    "layout(location = 0) in vec2 corner;\n"   /* (-1,-1)..(1,1) */
    "layout(location = 1) in vec2 center_px;\n"
    "layout(location = 2) in vec3 color;\n"
    "uniform vec2 viewport_px;\n"
    "uniform float radius_px;\n"
    "out vec2 offset_px;\n"
    "out vec3 disc_color;\n"
    "void main() {\n"
    "    offset_px = corner * (radius_px + 1.0);\n"
    "    vec2 p = center_px + offset_px;\n"
    "    gl_Position = vec4(2.0 * p.x / viewport_px.x - 1.0, 1.0 - 2.0 * p.y / viewport_px.y, 0.0, 1.0);\n"
    "    disc_color = color;\n"
    "}\n";

/* Coverage of a disc of radius r at distance d from its centre, over a one-pixel-wide edge; a disc smaller
 * than a pixel fades with its area rather than vanishing. */
static const char *fragment_shader =
    "#version 330 core\n"
    "in vec2 offset_px;\n"
    "in vec3 disc_color;\n"
    "uniform float radius_px;\n"
    "out vec4 frag;\n"
    "void main() {\n"
    "    float coverage = clamp(radius_px + 0.5 - length(offset_px), 0.0, 1.0);\n"
    "    coverage *= min(1.0, 2.0 * radius_px);\n"
    "    if (coverage <= 0.0) discard;\n"
    "    frag = vec4(disc_color, coverage);\n"
    "}\n";

static GLuint compile(GLenum kind, const char *source, char *err, size_t err_len)
{
    GLuint shader = glCreateShader(kind);
    glShaderSource(shader, 1, &source, NULL);
    glCompileShader(shader);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[512];
        glGetShaderInfoLog(shader, sizeof log, NULL, log);
        snprintf(err, err_len, "OpenGL shader does not compile: %s", log);
        glDeleteShader(shader);
        return 0;
    }
    return shader;
}

static int build_program(surge_canvas *c, char *err, size_t err_len)
{
    GLuint vs = compile(GL_VERTEX_SHADER, vertex_shader, err, err_len);
    GLuint fs = vs ? compile(GL_FRAGMENT_SHADER, fragment_shader, err, err_len) : 0;
    if (!fs)
        return -1;
    c->program = glCreateProgram();
    glAttachShader(c->program, vs);
    glAttachShader(c->program, fs);
    glLinkProgram(c->program);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = 0;
    glGetProgramiv(c->program, GL_LINK_STATUS, &ok);
    if (!ok) {
        snprintf(err, err_len, "OpenGL program does not link");
        return -1;
    }
    c->uniform_viewport = glGetUniformLocation(c->program, "viewport_px");
    c->uniform_radius = glGetUniformLocation(c->program, "radius_px");
    static const float quad[] = {-1, -1, 1, -1, -1, 1, 1, 1};
    glGenVertexArrays(1, &c->vao);
    glBindVertexArray(c->vao);
    glGenBuffers(1, &c->quad_vbo);
    glBindBuffer(GL_ARRAY_BUFFER, c->quad_vbo);
    glBufferData(GL_ARRAY_BUFFER, sizeof quad, quad, GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 0, NULL);
    glGenBuffers(1, &c->instance_vbo);
    glBindBuffer(GL_ARRAY_BUFFER, c->instance_vbo);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, sizeof(instance), (void *)offsetof(instance, x_px));
    glVertexAttribDivisor(1, 1);
    glEnableVertexAttribArray(2);
    glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, sizeof(instance), (void *)offsetof(instance, r));
    glVertexAttribDivisor(2, 1);
    return glGetError() == GL_NO_ERROR ? 0 : (snprintf(err, err_len, "OpenGL set-up failed"), -1);
}

surge_canvas *surge_canvas_create(int width_px, int height_px, const char *font_path, char *err, size_t err_len)
{
    if (width_px < 16 || height_px < 16 || width_px > 8192 || height_px > 8192) {
        snprintf(err, err_len, "frame size %d x %d px is outside 16..8192 px", width_px, height_px);
        return NULL;
    }
    surge_canvas *c = calloc(1, sizeof *c);
    if (!c) {
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    c->width = width_px;
    c->height = height_px;
    c->grown_min = c->grown_max = NAN;
    c->pixels = malloc((size_t)width_px * (size_t)height_px * 4);
    c->text = c->pixels ? surge_text_open(font_path ? font_path : SURGE_DEFAULT_FONT, width_px, height_px, err, err_len) : NULL;
    if (!c->text) {
        if (!c->pixels)
            snprintf(err, err_len, "out of memory for a %d x %d frame", width_px, height_px);
        surge_canvas_destroy(c);
        return NULL;
    }
    const int attributes[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 0, OSMESA_STENCIL_BITS, 0,
                              OSMESA_PROFILE, OSMESA_CORE_PROFILE, OSMESA_CONTEXT_MAJOR_VERSION, 3,
                              OSMESA_CONTEXT_MINOR_VERSION, 3, 0};
    c->context = OSMesaCreateContextAttribs(attributes, NULL);
    if (!c->context || surge_canvas_bind(c) != 0) {
        snprintf(err, err_len, "cannot create an OSMesa OpenGL 3.3 context (libosmesa6)");
        surge_canvas_destroy(c);
        return NULL;
    }
    if (build_program(c, err, err_len) != 0) {
        surge_canvas_destroy(c);
        return NULL;
    }
    return c;
}

int surge_canvas_bind(surge_canvas *c)
{
    if (!OSMesaMakeCurrent(c->context, c->pixels, GL_UNSIGNED_BYTE, c->width, c->height))
        return -1;
    OSMesaPixelStore(OSMESA_Y_UP, 0);
    return 0;
}

void surge_canvas_destroy(surge_canvas *c)
{
    if (!c)
        return;
    if (c->context) {
        if (c->program && surge_canvas_bind(c) == 0) {
            glDeleteBuffers(1, &c->quad_vbo);
            glDeleteBuffers(1, &c->instance_vbo);
            glDeleteVertexArrays(1, &c->vao);
            glDeleteProgram(c->program);
        }
        OSMesaDestroyContext(c->context);
    }
    surge_text_close(c->text);
    free(c->instances);
    free(c->pixels);
    free(c);
}

const surge_canvas_layout *surge_canvas_last_layout(const surge_canvas *c) { return &c->layout; }

const uint8_t *surge_canvas_pixels(const surge_canvas *c) { return c->pixels; }

void surge_colormap_rgb(int colormap, double value, double min, double max, uint8_t rgb[3])
{
    double u = max > min ? (value - min) / (max - min) : 0.5;
    u = !(u > 0) ? 0 : (u > 1 ? 1 : u); /* a NaN value takes the low end */
    const int k = (int)lround(u * 255.0);
    const unsigned char(*table)[3] = surge_colormap_table((surge_colormap)colormap);
    memcpy(rgb, table[k], 3);
}

/* ---- round numbers ---- */

/* The 1, 2 or 5 times a power of ten nearest to x > 0 (on a log scale). */
static double nice_step(double x)
{
    const double decade = pow(10.0, floor(log10(x))), f = x / decade;
    return decade * (f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10);
}

/* The tick spacing for a range: a round step giving about five intervals. */
static double tick_step(double lo, double hi)
{
    return nice_step((hi - lo) / 5.0);
}

void surge_render_round_range(double *lo, double *hi)
{
    if (!(*hi > *lo) || !isfinite(*hi - *lo))
        return;
    const double step = tick_step(*lo, *hi);
    *lo = floor(*lo / step * (1 + 1e-12)) * step;
    *hi = ceil(*hi / step * (1 - 1e-12)) * step;
}

/* ---- the view ---- */

static double field_value(const surge_snapshot *s, int i, int field, double belt_mps)
{
    switch (field) {
    case SURGE_FIELD_VX_REL: return s->vx_mps[i] - belt_mps;
    case SURGE_FIELD_VX: return s->vx_mps[i];
    case SURGE_FIELD_PRESSURE: return s->pressure_pa[i];
    case SURGE_FIELD_DENSITY: return s->density_kgpm3[i];
    default: return hypot(s->vx_mps[i], s->vy_mps[i]);
    }
}

/* The bed frame (x along the bed, y normal) or, with true_slope, the world frame with gravity down. */
static void world_position(const surge_snapshot *s, int i, double cos_t, double sin_t, double *X, double *Y)
{
    *X = s->x_m[i] * cos_t + s->y_m[i] * sin_t;
    *Y = -s->x_m[i] * sin_t + s->y_m[i] * cos_t;
}

/* The x window along the bed the view shows. */
static void view_window(const surge_snapshot *s, const surge_params *p, double *x0, double *x1)
{
    *x0 = -INFINITY;
    *x1 = INFINITY;
    if (p->render.view == SURGE_VIEW_FIXED) {
        *x0 = p->render.view_x0_m;
        *x1 = p->render.view_x1_m;
    } else if (p->render.view == SURGE_VIEW_FOLLOW) {
        double front = -INFINITY;
        for (int i = 0; i < s->count; i++)
            if (s->kind[i] == SURGE_KIND_FLUID && s->x_m[i] > front)
                front = s->x_m[i];
        if (!isfinite(front))
            front = 0;
        *x0 = front - 0.75 * p->render.view_width_m;
        *x1 = front + 0.25 * p->render.view_width_m;
    }
}

static int layout_view(surge_canvas *c, const surge_snapshot *s, const surge_params *p, double belt_mps)
{
    surge_canvas_layout *l = &c->layout;
    const int W = c->width, H = c->height;
    l->plot_x0 = (int)(0.03 * W);
    l->plot_x1 = (int)(0.86 * W);
    l->plot_y0 = (int)(0.10 * H);
    l->plot_y1 = (int)(0.86 * H);
    l->colorbar_x0 = (int)(0.885 * W);
    l->colorbar_x1 = l->colorbar_x0 + (int)fmax(4, 0.015 * W);
    l->colorbar_y0 = l->plot_y0 + (int)(0.06 * H);
    l->colorbar_y1 = l->plot_y1;
    const double slope = p->render.true_slope ? p->body.slope_deg * pi / 180.0 : 0.0;
    const double cos_t = cos(slope), sin_t = sin(slope);
    double wx0, wx1;
    view_window(s, p, &wx0, &wx1);
    double X0 = INFINITY, X1 = -INFINITY, Y0 = INFINITY, Y1 = -INFINITY;
    double vmin = INFINITY, vmax = -INFINITY;
    for (int i = 0; i < s->count; i++) {
        if (s->x_m[i] < wx0 || s->x_m[i] > wx1)
            continue;
        double X, Y;
        world_position(s, i, cos_t, sin_t, &X, &Y);
        X0 = fmin(X0, X);
        X1 = fmax(X1, X);
        Y0 = fmin(Y0, Y);
        Y1 = fmax(Y1, Y);
        if (s->kind[i] == SURGE_KIND_FLUID) {
            const double v = field_value(s, i, p->render.field, belt_mps);
            vmin = fmin(vmin, v);
            vmax = fmax(vmax, v);
        }
    }
    if (!(X1 >= X0)) { /* nothing in the window: show the window itself */
        X0 = isfinite(wx0) ? wx0 : 0;
        X1 = isfinite(wx1) ? wx1 : 1;
        Y0 = 0;
        Y1 = 0.1 * (X1 - X0);
    }
    if (p->render.view != SURGE_VIEW_WHOLE && !p->render.true_slope) {
        X0 = wx0; /* the window's own width, even where it holds no particles */
        X1 = wx1;
    }
    const double margin = p->numerics.dp_m;
    X0 -= margin, X1 += margin, Y0 -= margin, Y1 += margin;
    const double plot_w = l->plot_x1 - l->plot_x0, plot_h = l->plot_y1 - l->plot_y0;
    l->scale_px_per_m = fmin(plot_w / (X1 - X0), plot_h / (Y1 - Y0));
    /* centred across, resting on the bottom of the plot area */
    l->world_x0_m = 0.5 * (X0 + X1) - 0.5 * plot_w / l->scale_px_per_m;
    l->world_y0_m = Y0;
    l->radius_px = 0.5 * p->numerics.dp_m * l->scale_px_per_m;
    l->field_min = isfinite(vmin) ? vmin : NAN;
    l->field_max = isfinite(vmax) ? vmax : NAN;
    if (p->render.color_max > p->render.color_min) {
        l->color_min = p->render.color_min;
        l->color_max = p->render.color_max;
    } else if (vmax > vmin) {
        /* while a run renders, the range grows to round numbers and never shrinks, so a colour keeps its
         * meaning except when the flow leaves the range (surge render instead takes all frames' range) */
        if (!(c->grown_max > c->grown_min) || vmin < c->grown_min || vmax > c->grown_max) {
            c->grown_min = c->grown_max > c->grown_min ? fmin(vmin, c->grown_min) : vmin;
            c->grown_max = c->grown_max > c->grown_min ? fmax(vmax, c->grown_max) : vmax;
            surge_render_round_range(&c->grown_min, &c->grown_max);
        }
        l->color_min = c->grown_min;
        l->color_max = c->grown_max;
    } else { /* one value everywhere (a fluid at rest): a unit range from it, not below zero for a speed */
        const double low = !isfinite(vmin) ? 0 : p->render.field == SURGE_FIELD_SPEED ? vmin : vmin - 0.5;
        l->color_min = low;
        l->color_max = low + 1;
    }
    return 0;
}

static int fill_instances(surge_canvas *c, const surge_snapshot *s, const surge_params *p, double belt_mps)
{
    if (s->count > c->instance_capacity) {
        instance *grown = realloc(c->instances, (size_t)s->count * sizeof *grown);
        if (!grown)
            return -1;
        c->instances = grown;
        c->instance_capacity = s->count;
    }
    const surge_canvas_layout *l = &c->layout;
    const double slope = p->render.true_slope ? p->body.slope_deg * pi / 180.0 : 0.0;
    const double cos_t = cos(slope), sin_t = sin(slope);
    /* walls first, fluid on top */
    int n = 0;
    for (int pass = 0; pass < 2; pass++)
        for (int i = 0; i < s->count; i++) {
            const int fluid = s->kind[i] == SURGE_KIND_FLUID;
            if (fluid != pass)
                continue;
            double X, Y;
            world_position(s, i, cos_t, sin_t, &X, &Y);
            uint8_t rgb[3];
            if (fluid)
                surge_colormap_rgb(p->render.colormap, field_value(s, i, p->render.field, belt_mps), l->color_min,
                                   l->color_max, rgb);
            else if (s->kind[i] == SURGE_KIND_BOULDER)
                memcpy(rgb, boulder_colour(s, i, p), 3);
            else
                memcpy(rgb, s->kind[i] == SURGE_KIND_MOVING_WALL ? belt_rgb : wall_rgb, 3);
            instance *in = &c->instances[n++];
            in->x_px = (float)(l->plot_x0 + (X - l->world_x0_m) * l->scale_px_per_m);
            in->y_px = (float)(l->plot_y1 - (Y - l->world_y0_m) * l->scale_px_per_m);
            in->r = rgb[0] / 255.0f;
            in->g = rgb[1] / 255.0f;
            in->b = rgb[2] / 255.0f;
        }
    return n;
}

/* ---- overlays, on the CPU ---- */

static void fill_rect(surge_canvas *c, int x0, int y0, int x1, int y1, const uint8_t rgb[3])
{
    x0 = x0 < 0 ? 0 : x0;
    y0 = y0 < 0 ? 0 : y0;
    x1 = x1 > c->width ? c->width : x1;
    y1 = y1 > c->height ? c->height : y1;
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++) {
            uint8_t *px = c->pixels + 4 * ((size_t)y * c->width + x);
            px[0] = rgb[0], px[1] = rgb[1], px[2] = rgb[2], px[3] = 255;
        }
}

static void outline_rect(surge_canvas *c, int x0, int y0, int x1, int y1)
{
    fill_rect(c, x0 - 1, y0 - 1, x1 + 1, y0, ink_rgb);
    fill_rect(c, x0 - 1, y1, x1 + 1, y1 + 1, ink_rgb);
    fill_rect(c, x0 - 1, y0, x0, y1, ink_rgb);
    fill_rect(c, x1, y0, x1 + 1, y1, ink_rgb);
}

/* A line of the given width in pixels, and an arrow: the line with a head at (x1, y1). */
static void draw_line(surge_canvas *c, double x0, double y0, double x1, double y1, int width)
{
    const int steps = 1 + (int)fmax(fabs(x1 - x0), fabs(y1 - y0));
    for (int k = 0; k <= steps; k++) {
        const int x = (int)lround(x0 + (x1 - x0) * k / steps), y = (int)lround(y0 + (y1 - y0) * k / steps);
        fill_rect(c, x - width / 2, y - width / 2, x - width / 2 + width, y - width / 2 + width, ink_rgb);
    }
}

static void draw_arrow(surge_canvas *c, double x0, double y0, double x1, double y1, int width)
{
    const double length = hypot(x1 - x0, y1 - y0), ux = (x1 - x0) / length, uy = (y1 - y0) / length;
    const double head = 0.3 * length;
    draw_line(c, x0, y0, x1, y1, width);
    for (int side = -1; side <= 1; side += 2)
        draw_line(c, x1, y1, x1 - head * (ux * 0.87 - side * uy * 0.5), y1 - head * (uy * 0.87 + side * ux * 0.5), width);
}

/* What drives the flow, drawn: gravity (its direction in the picture, the bed along x unless true_slope) in the
 * plot's top right corner, and the belt's direction under the plot's right end. */
static void draw_drivers(surge_canvas *c, const surge_params *p)
{
    const surge_canvas_layout *l = &c->layout;
    const int size = surge_text_size(c->text), width = size / 8 > 1 ? size / 8 : 1;
    const double slope = p->body.slope_deg * pi / 180.0, arrow = 2.0 * size;
    if (p->body.gravity_mps2 > 0) {
        const double gx = p->render.true_slope ? 0 : sin(slope), gy = p->render.true_slope ? 1 : cos(slope);
        const double x0 = l->plot_x1 - 1.5 * size - fmax(0, gx) * arrow, y0 = l->plot_y0 + 0.5 * size;
        draw_arrow(c, x0, y0, x0 + gx * arrow, y0 + gy * arrow, width);
        surge_text_draw(c->text, c->pixels, c->width, c->height, (int)(x0 - 1.2 * size), (int)(y0 + size), "g",
                        ink_rgb);
    }
    if (p->walls.bottom && p->walls.bottom_speed_mps != 0) {
        const double direction = p->walls.bottom_speed_mps > 0 ? 1 : -1, y = c->height - 1.25 * size;
        const double x_mid = l->plot_x1 - 3 * size;
        draw_arrow(c, x_mid - direction * arrow / 2, y, x_mid + direction * arrow / 2, y, width);
        surge_text_draw(c->text, c->pixels, c->width, c->height, (int)(x_mid - arrow / 2 - 3.2 * size),
                        (int)(y + size / 3), "belt", ink_rgb);
    }
}

static const char *field_label(int field)
{
    static const char *const labels[] = {"speed (m/s)", "vx - belt (m/s)", "vx (m/s)", "pressure (Pa)",
                                         "density (kg/m\xc2\xb3)"};
    return field >= 0 && field < 5 ? labels[field] : "?";
}

static void draw_colorbar(surge_canvas *c, const surge_params *p)
{
    const surge_canvas_layout *l = &c->layout;
    const int h = l->colorbar_y1 - l->colorbar_y0;
    for (int y = l->colorbar_y0; y < l->colorbar_y1; y++) {
        uint8_t rgb[3];
        const double u = 1.0 - (y - l->colorbar_y0 + 0.5) / h; /* top = max */
        surge_colormap_rgb(p->render.colormap, l->color_min + u * (l->color_max - l->color_min), l->color_min,
                           l->color_max, rgb);
        fill_rect(c, l->colorbar_x0, y, l->colorbar_x1, y + 1, rgb);
    }
    outline_rect(c, l->colorbar_x0, l->colorbar_y0, l->colorbar_x1, l->colorbar_y1);
    const int size = surge_text_size(c->text);
    /* ticks at round values inside the range, labelled with as many decimals as the step needs */
    const double span = l->color_max - l->color_min, step = tick_step(l->color_min, l->color_max);
    const int decimals = step >= 1 ? 0 : (int)ceil(-log10(step) - 1e-9);
    const int plain = step >= 1e-4 && step < 1e6;
    for (double k = ceil(l->color_min / step - 1e-9); k * step <= l->color_max + 1e-9 * span; k++) {
        const double value = fabs(k) < 0.5 ? 0 : k * step; /* 0, not 2.3e-10 */
        const int y = l->colorbar_y1 - (int)lround((value - l->color_min) / span * h);
        fill_rect(c, l->colorbar_x1, y, l->colorbar_x1 + size / 3, y + 1, ink_rgb);
        char label[32];
        if (plain)
            snprintf(label, sizeof label, "%.*f", decimals, value);
        else
            snprintf(label, sizeof label, "%.2g", value);
        surge_text_draw(c->text, c->pixels, c->width, c->height, l->colorbar_x1 + size / 2, y + size / 3, label,
                        ink_rgb);
    }
    surge_text_draw(c->text, c->pixels, c->width, c->height, l->colorbar_x0 - size, l->colorbar_y0 - size,
                    field_label(p->render.field), ink_rgb);
}

/* A bar of a round length (1, 2 or 5 times a power of ten) near a fifth of the plot width. */
static void draw_length_scale(surge_canvas *c)
{
    const surge_canvas_layout *l = &c->layout;
    const double target_m = 0.2 * (l->plot_x1 - l->plot_x0) / l->scale_px_per_m;
    const double decade = pow(10.0, floor(log10(target_m)));
    const double length_m = target_m >= 5 * decade ? 5 * decade : (target_m >= 2 * decade ? 2 * decade : decade);
    const int px = (int)lround(length_m * l->scale_px_per_m);
    const int size = surge_text_size(c->text);
    const int x0 = l->plot_x0, y = c->height - size;
    fill_rect(c, x0, y - size / 4, x0 + px, y, ink_rgb);
    char label[32];
    if (length_m >= 1)
        snprintf(label, sizeof label, "%g m", length_m);
    else if (length_m >= 0.01)
        snprintf(label, sizeof label, "%g cm", length_m * 100);
    else
        snprintf(label, sizeof label, "%g mm", length_m * 1000);
    surge_text_draw(c->text, c->pixels, c->width, c->height, x0 + px + size / 2, y, label, ink_rgb);
}

/* The speed of the belt in a snapshot: the lowest moving wall (a moving lid is not one); 0 without. */
static double snapshot_belt_mps(const surge_snapshot *s)
{
    double belt_mps = 0, belt_y_m = INFINITY;
    for (int i = 0; i < s->count; i++)
        if (s->kind[i] == SURGE_KIND_MOVING_WALL && s->y_m[i] < belt_y_m) {
            belt_mps = s->vx_mps[i];
            belt_y_m = s->y_m[i];
        }
    return belt_mps;
}

int surge_render_fitted_height_px(int width_px, const surge_snapshot *s, const surge_params *p)
{
    const double slope = p->render.true_slope ? p->body.slope_deg * pi / 180.0 : 0.0;
    const double cos_t = cos(slope), sin_t = sin(slope);
    double wx0, wx1;
    view_window(s, p, &wx0, &wx1);
    if (p->render.view == SURGE_VIEW_FOLLOW)
        wx0 = -INFINITY, wx1 = INFINITY; /* the window moves: its height is the walls' along the whole bed */
    double X0 = INFINITY, X1 = -INFINITY, Y0 = INFINITY, Y1 = -INFINITY;
    for (int pass = 0; pass < 2 && !(X1 > X0); pass++) /* the fixed walls; every particle when there are none */
        for (int i = 0; i < s->count; i++) {
            const int fixed_wall = s->kind[i] == SURGE_KIND_WALL || s->kind[i] == SURGE_KIND_MOVING_WALL;
            if ((pass == 0 && !fixed_wall) || s->x_m[i] < wx0 || s->x_m[i] > wx1)
                continue;
            double X, Y;
            world_position(s, i, cos_t, sin_t, &X, &Y);
            X0 = fmin(X0, X), X1 = fmax(X1, X), Y0 = fmin(Y0, Y), Y1 = fmax(Y1, Y);
        }
    if (p->render.view != SURGE_VIEW_WHOLE && !p->render.true_slope) {
        X0 = p->render.view == SURGE_VIEW_FIXED ? p->render.view_x0_m : 0;
        X1 = p->render.view == SURGE_VIEW_FIXED ? p->render.view_x1_m : p->render.view_width_m;
    }
    const double margin = 2 * p->numerics.dp_m;
    const double aspect = (X1 > X0 && Y1 >= Y0) ? (Y1 - Y0 + margin) / (X1 - X0 + margin) : 0.5625;
    /* the plot is 83 % of the width and 76 % of the height (layout_view); a fifth of the width at least, for the
     * colour bar and its labels, and square at most */
    const double height = fmin(fmax(0.83 * width_px * aspect / 0.76, 0.2 * width_px), width_px);
    const int even = 2 * (int)lround(0.5 * height); /* video encoders want even sizes */
    return even < 16 ? 16 : even > 8192 ? 8192 : even;
}

const surge_canvas_layout *surge_canvas_layout_only(surge_canvas *c, const surge_snapshot *s, const surge_params *p)
{
    return layout_view(c, s, p, snapshot_belt_mps(s)) == 0 ? &c->layout : NULL;
}

const uint8_t *surge_canvas_draw(surge_canvas *c, const surge_snapshot *s, const surge_params *p)
{
    const double belt_mps = snapshot_belt_mps(s);
    if (layout_view(c, s, p, belt_mps) != 0)
        return NULL;
    const int n = fill_instances(c, s, p, belt_mps);
    if (n < 0)
        return NULL;
    const surge_canvas_layout *l = &c->layout;
    glViewport(0, 0, c->width, c->height);
    glDisable(GL_SCISSOR_TEST);
    glClearColor(background_rgb[0] / 255.0f, background_rgb[1] / 255.0f, background_rgb[2] / 255.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    glEnable(GL_SCISSOR_TEST); /* particles stay inside the plot area; GL's y runs up from the bottom */
    glScissor(l->plot_x0, c->height - l->plot_y1, l->plot_x1 - l->plot_x0, l->plot_y1 - l->plot_y0);
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glUseProgram(c->program);
    glUniform2f(c->uniform_viewport, (float)c->width, (float)c->height);
    glUniform1f(c->uniform_radius, (float)l->radius_px);
    glBindVertexArray(c->vao);
    glBindBuffer(GL_ARRAY_BUFFER, c->instance_vbo);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)((size_t)n * sizeof(instance)), c->instances, GL_STREAM_DRAW);
    glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, n);
    glFinish();
    if (glGetError() != GL_NO_ERROR)
        return NULL;

    outline_rect(c, l->plot_x0, l->plot_y0, l->plot_x1, l->plot_y1);
    draw_colorbar(c, p);
    draw_length_scale(c);
    draw_drivers(c, p);
    char label[160];
    /* the time, and what drives the flow: the slope and the belt */
    int used = snprintf(label, sizeof label, "t = %.3f s", s->time_s);
    if (p->body.slope_deg != 0 && used > 0 && used < (int)sizeof label)
        used += snprintf(label + used, sizeof label - (size_t)used, "   slope %.3g deg", p->body.slope_deg);
    if (p->walls.bottom && p->walls.bottom_speed_mps != 0 && used > 0 && used < (int)sizeof label)
        used += snprintf(label + used, sizeof label - (size_t)used, "   belt %.3g m/s", p->walls.bottom_speed_mps);
    /* the discs and their solid fraction, over the initial fluid block's area (docs/validation/debris_surge.md) */
    const double block_m2 = (p->fluid.x1_m - p->fluid.x0_m) * p->fluid.depth_m;
    if (s->boulders.count > 0 && block_m2 > 0 && used > 0 && used < (int)sizeof label) {
        double area = 0;
        for (int k = 0; k < s->boulders.count; k++)
            area += pi * s->boulders.radius_m[k] * s->boulders.radius_m[k];
        snprintf(label + used, sizeof label - (size_t)used, "   %d discs, phi %.2g", s->boulders.count,
                 area / block_m2);
    }
    const int size = surge_text_size(c->text);
    surge_text_draw(c->text, c->pixels, c->width, c->height, l->plot_x0, l->plot_y0 - size / 2, label, ink_rgb);
    return c->pixels;
}

int surge_canvas_png(const surge_canvas *c, uint8_t **png, size_t *png_len, char *err, size_t err_len)
{
    return surge_png_encode_rgba(c->pixels, c->width, c->height, png, png_len, err, err_len);
}
