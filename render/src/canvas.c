/* Drawing one snapshot off-screen: OSMesa context, walls (and, in the particles style, the fluid) as instanced
 * anti-aliased discs (OpenGL 3.3 core); then on the CPU the fluid as a field, the boulders as solid discs
 * (layers.c) and the overlays (colour bar, time, length scale) (see surge/render.h). */
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

#include "layers.h"
#include "png_io.h"

static const double pi = 3.14159265358979323846;
#include "colormaps.h"
#include "text.h"

/* Colours of what is not fluid (sRGB). */
static const uint8_t background_rgb[3] = {255, 255, 255};
static const uint8_t wall_rgb[3] = {150, 150, 150};  /* fixed walls: grey */
static const uint8_t belt_rgb[3] = {205, 110, 40};   /* the moving belt: orange-brown, outside both colour maps */
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
    surge_splat *splats;
    int splat_capacity;
    surge_field_sums sums;
    surge_canvas_layout layout;
    double grown_min, grown_max; /* an automatic colour range so far (NaN: none yet); it only grows */
    /* the view so far, which only grows (NaN: none yet), for the view and slope of view_key: a whole view's box, the
     * top of any view, and a periodic whole view's window along x */
    int view_key;
    double kept_x0, kept_x1, kept_y0, kept_y1, kept_window_x0, kept_window_x1;
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
    c->view_key = -1;
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
    free(c->splats);
    free(c->sums.weight);
    free(c->sums.weighted);
    free(c->sums.solid);
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

/* What the picture shows of the bed: a window along x and the picture's turn. */
typedef struct view_frame {
    double cos_t, sin_t;  /* the bed frame (x along the bed, y normal) or, with true_slope, gravity down */
    double x0_m, x1_m;    /* the window along the bed */
    double period_m;      /* > 0: a periodic domain, whose x is taken into [x0_m, x0_m + period_m) */
} view_frame;

/* x taken into the window's period. */
static double view_x(const view_frame *v, double x)
{
    return v->period_m > 0 && isfinite(v->x0_m) ? x - v->period_m * floor((x - v->x0_m) / v->period_m) : x;
}

static int in_view(const view_frame *v, double x)
{
    x = view_x(v, x);
    return x >= v->x0_m && x <= v->x1_m;
}

/* World coordinates of a point of the bed frame, x taken into the window. */
static void world_xy(const view_frame *v, double x, double y, double *X, double *Y)
{
    x = view_x(v, x);
    *X = x * v->cos_t + y * v->sin_t;
    *Y = -x * v->sin_t + y * v->cos_t;
}

/* The fluid's body along x, robust to particles carried ahead of it: the fluid counted in columns 2 dp wide, the
 * body the columns around the deepest one that hold at least a fifth of its particles, across gaps no wider than
 * the largest boulder (or one column). On a periodic domain x wraps, and front - back is at most the period.
 * Returns -1 without fluid. */
static int fluid_body(const surge_snapshot *s, const surge_params *p, double *back, double *front)
{
    const double period = p->domain.periodic_x ? p->domain.length_m : 0;
    double lo = period > 0 ? 0 : INFINITY, hi = period > 0 ? period : -INFINITY;
    for (int i = 0; i < s->count && period <= 0; i++)
        if (s->kind[i] == SURGE_KIND_FLUID)
            lo = fmin(lo, s->x_m[i]), hi = fmax(hi, s->x_m[i]);
    if (!(hi >= lo))
        return -1;
    const int columns = (int)fmin(1 << 16, ceil(fmax(hi - lo, 1e-12) / (2 * p->numerics.dp_m)));
    const double width = fmax(hi - lo, 1e-12) / columns;
    int *count = calloc((size_t)columns, sizeof *count), deepest = 0;
    if (!count)
        return -1;
    for (int i = 0; i < s->count; i++)
        if (s->kind[i] == SURGE_KIND_FLUID) {
            const double x = period > 0 ? s->x_m[i] - period * floor(s->x_m[i] / period) : s->x_m[i];
            count[(int)fmin(columns - 1, fmax(0, (x - lo) / width))]++;
        }
    for (int k = 1; k < columns; k++)
        deepest = count[k] > count[deepest] ? k : deepest;
    double largest_m = 0;
    for (int j = 0; j < s->boulders.count; j++)
        largest_m = fmax(largest_m, 2 * s->boulders.radius_m[j]);
    const int gap = (int)fmin(columns, fmax(1, ceil(largest_m / width))), enough = (int)ceil(0.2 * count[deepest]);
    int first = deepest, last = deepest; /* columns, unwrapped on a periodic domain */
    for (int dir = 1; dir >= -1; dir -= 2)
        for (int k = deepest + dir, missed = 0; missed <= gap && last - first + 1 < columns; k += dir) {
            const int at = period > 0 ? ((k % columns) + columns) % columns : k;
            if (at < 0 || at >= columns)
                break;
            missed = count[at] >= enough ? 0 : missed + 1;
            if (!missed)
                *(dir > 0 ? &last : &first) = k;
        }
    free(count);
    *back = lo + first * width;
    *front = lo + (last + 1) * width;
    return 0;
}

/* A periodic whole view: the period's part the fluid's body holds, 4 % of its length and 2 dp added either
 * side, grown from the canvas's earlier frames (shifted by periods to meet them), at most one period. */
static void periodic_whole_window(surge_canvas *c, const surge_snapshot *s, const surge_params *p, double *x0,
                                  double *x1)
{
    const double period = p->domain.length_m;
    double back, front;
    if (fluid_body(s, p, &back, &front) != 0)
        back = 0, front = period;
    const double margin = 0.04 * (front - back) + 2 * p->numerics.dp_m;
    back -= margin, front += margin;
    if (isfinite(c->kept_window_x0)) {
        const double shift = period * round((0.5 * (c->kept_window_x0 + c->kept_window_x1) - 0.5 * (back + front)) /
                                            period);
        back = fmin(back + shift, c->kept_window_x0);
        front = fmax(front + shift, c->kept_window_x1);
    }
    if (front - back > period)
        front = back + period;
    *x0 = c->kept_window_x0 = back;
    *x1 = c->kept_window_x1 = front;
}

/* The window along the bed the view shows, and the picture's turn. */
static void view_window(surge_canvas *c, const surge_snapshot *s, const surge_params *p, view_frame *v)
{
    const double slope = p->render.true_slope ? p->body.slope_deg * pi / 180.0 : 0.0;
    v->cos_t = cos(slope);
    v->sin_t = sin(slope);
    v->x0_m = -INFINITY;
    v->x1_m = INFINITY;
    v->period_m = p->domain.periodic_x ? p->domain.length_m : 0;
    double back, front;
    if (p->render.view == SURGE_VIEW_FIXED) {
        v->x0_m = p->render.view_x0_m;
        v->x1_m = p->render.view_x1_m;
    } else if (p->render.view == SURGE_VIEW_FOLLOW) {
        if (fluid_body(s, p, &back, &front) != 0)
            front = 0;
        v->x0_m = front - 0.75 * p->render.view_width_m;
        v->x1_m = front + 0.25 * p->render.view_width_m;
    } else if (v->period_m > 0) {
        periodic_whole_window(c, s, p, &v->x0_m, &v->x1_m);
    }
}

/* The box of the world the view shows: the particles in its window, from the bottom of the bed to a little above
 * the fluid and the boulders (a tall wall is cut); the field's range over the fluid there. */
static void view_box(const surge_snapshot *s, const surge_params *p, const view_frame *v, double belt_mps,
                     double box[4], double *vmin, double *vmax)
{
    double top = -INFINITY;
    box[0] = box[2] = INFINITY;
    box[1] = box[3] = -INFINITY;
    *vmin = INFINITY;
    *vmax = -INFINITY;
    for (int i = 0; i < s->count; i++) {
        if (!in_view(v, s->x_m[i]))
            continue;
        double X, Y;
        world_xy(v, s->x_m[i], s->y_m[i], &X, &Y);
        box[0] = fmin(box[0], X), box[1] = fmax(box[1], X), box[2] = fmin(box[2], Y), box[3] = fmax(box[3], Y);
        if (s->kind[i] == SURGE_KIND_FLUID || s->kind[i] == SURGE_KIND_BOULDER)
            top = fmax(top, Y);
        if (s->kind[i] == SURGE_KIND_FLUID) {
            const double value = field_value(s, i, p->render.field, belt_mps);
            *vmin = fmin(*vmin, value);
            *vmax = fmax(*vmax, value);
        }
    }
    if (isfinite(top))
        box[3] = fmin(box[3], top + 0.15 * (top - box[2]) + p->numerics.dp_m);
}

/* The view's box grown from the canvas's earlier frames with the same view and slope, so that the scale holds
 * through a movie: a whole view's extent, any view's top. */
static void keep_box(surge_canvas *c, const surge_params *p, double box[4])
{
    const int key = p->render.view * 2 + (p->render.true_slope ? 1 : 0);
    if (key != c->view_key) {
        c->view_key = key;
        c->kept_x0 = c->kept_x1 = c->kept_y0 = c->kept_y1 = NAN;
        c->kept_window_x0 = c->kept_window_x1 = NAN;
        return;
    }
    if (p->render.view == SURGE_VIEW_WHOLE && isfinite(c->kept_x0)) {
        box[0] = fmin(box[0], c->kept_x0), box[1] = fmax(box[1], c->kept_x1);
        box[2] = fmin(box[2], c->kept_y0);
    }
    if (isfinite(c->kept_y1))
        box[3] = fmax(box[3], c->kept_y1);
}

static void set_colour_range(surge_canvas *c, const surge_params *p, double vmin, double vmax)
{
    surge_canvas_layout *l = &c->layout;
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
}

static int layout_view(surge_canvas *c, const surge_snapshot *s, const surge_params *p, double belt_mps,
                       view_frame *v)
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
    view_window(c, s, p, v);
    double box[4], vmin, vmax;
    view_box(s, p, v, belt_mps, box, &vmin, &vmax);
    if (!(box[1] >= box[0])) { /* nothing in the window: show the window itself */
        box[0] = isfinite(v->x0_m) ? v->x0_m : 0;
        box[1] = isfinite(v->x1_m) ? v->x1_m : 1;
        box[2] = 0;
        box[3] = 0.1 * (box[1] - box[0]);
    }
    if (p->render.view != SURGE_VIEW_WHOLE && !p->render.true_slope) {
        box[0] = v->x0_m; /* the window's own width, even where it holds no particles */
        box[1] = v->x1_m;
    }
    keep_box(c, p, box);
    c->kept_x0 = box[0], c->kept_x1 = box[1], c->kept_y0 = box[2], c->kept_y1 = box[3];
    const double margin = p->numerics.dp_m;
    const double X0 = box[0] - margin, X1 = box[1] + margin, Y0 = box[2] - margin, Y1 = box[3] + margin;
    const double plot_w = l->plot_x1 - l->plot_x0, plot_h = l->plot_y1 - l->plot_y0;
    l->scale_px_per_m = fmin(plot_w / (X1 - X0), plot_h / (Y1 - Y0));
    /* centred across, resting on the bottom of the plot area */
    l->world_x0_m = 0.5 * (X0 + X1) - 0.5 * plot_w / l->scale_px_per_m;
    l->world_y0_m = Y0;
    l->view_x0_m = v->x0_m;
    l->view_x1_m = v->x1_m;
    l->radius_px = 0.5 * p->numerics.dp_m * l->scale_px_per_m;
    set_colour_range(c, p, vmin, vmax);
    return 0;
}

/* Pixel position of a point of the bed frame. */
static void to_pixels(const surge_canvas_layout *l, const view_frame *v, double x, double y, float *px, float *py)
{
    double X, Y;
    world_xy(v, x, y, &X, &Y);
    *px = (float)(l->plot_x0 + (X - l->world_x0_m) * l->scale_px_per_m);
    *py = (float)(l->plot_y1 - (Y - l->world_y0_m) * l->scale_px_per_m);
}

/* The GL discs: walls, then (particles style) the fluid on top, and a boulder's particles where the snapshot has no
 * boulder states to draw its disc from. Returns their number, -1 when out of memory. */
static int fill_instances(surge_canvas *c, const surge_snapshot *s, const surge_params *p, const view_frame *v,
                          double belt_mps)
{
    if (s->count > c->instance_capacity) {
        instance *grown = realloc(c->instances, (size_t)s->count * sizeof *grown);
        if (!grown)
            return -1;
        c->instances = grown;
        c->instance_capacity = s->count;
    }
    const surge_canvas_layout *l = &c->layout;
    const int fluid_dots = p->render.style == SURGE_STYLE_PARTICLES, boulder_dots = s->boulders.count == 0;
    int n = 0;
    for (int pass = 0; pass < 2; pass++)
        for (int i = 0; i < s->count; i++) {
            const int kind = s->kind[i], fluid = kind == SURGE_KIND_FLUID;
            if (fluid != pass || (fluid && !fluid_dots) || (kind == SURGE_KIND_BOULDER && !boulder_dots))
                continue;
            uint8_t rgb[3];
            if (fluid)
                surge_colormap_rgb(p->render.colormap, field_value(s, i, p->render.field, belt_mps), l->color_min,
                                   l->color_max, rgb);
            else
                memcpy(rgb, kind == SURGE_KIND_BOULDER ? surge_disc_body_rgb
                            : kind == SURGE_KIND_MOVING_WALL ? belt_rgb : wall_rgb, 3);
            instance *in = &c->instances[n++];
            to_pixels(l, v, s->x_m[i], s->y_m[i], &in->x_px, &in->y_px);
            in->r = rgb[0] / 255.0f;
            in->g = rgb[1] / 255.0f;
            in->b = rgb[2] / 255.0f;
        }
    return n;
}

/* The field style's fluid (layers.c) and the boulders' discs, over the GL image in the plot area. Returns 0, or -1
 * when out of memory. */
static int draw_layers(surge_canvas *c, const surge_snapshot *s, const surge_params *p, const view_frame *v,
                       double belt_mps)
{
    const surge_canvas_layout *l = &c->layout;
    const surge_layer_target t = {c->pixels, c->width, l->plot_x0, l->plot_y0, l->plot_x1, l->plot_y1};
    if (p->render.style == SURGE_STYLE_FIELD) {
        if (s->count > c->splat_capacity) {
            surge_splat *grown = realloc(c->splats, (size_t)s->count * sizeof *grown);
            if (!grown)
                return -1;
            c->splats = grown;
            c->splat_capacity = s->count;
        }
        int n[2] = {0, 0}; /* the fluid first, then the solids */
        for (int pass = 0; pass < 2; pass++)
            for (int i = 0; i < s->count; i++)
                if ((s->kind[i] == SURGE_KIND_FLUID) == (pass == 0)) {
                    surge_splat *sp = &c->splats[n[0] + n[1]];
                    to_pixels(l, v, s->x_m[i], s->y_m[i], &sp->x_px, &sp->y_px);
                    sp->value = pass == 0 ? (float)field_value(s, i, p->render.field, belt_mps) : 0;
                    n[pass]++;
                }
        if (surge_draw_field(&c->sums, &t, c->splats, n[0], n[1], 2 * l->radius_px, p->render.colormap,
                             l->color_min, l->color_max) != 0)
            return -1;
    }
    const double slope = p->render.true_slope ? p->body.slope_deg * pi / 180.0 : 0.0;
    const surge_boulder_state *b = &s->boulders;
    for (int j = 0; j < b->count; j++)
        for (int image = v->period_m > 0 ? -1 : 0; image <= (v->period_m > 0 ? 1 : 0); image++) {
            float x, y;
            to_pixels(l, v, b->x_m[j], b->y_m[j], &x, &y);
            const double shift_px = image * v->period_m * l->scale_px_per_m; /* a periodic image */
            surge_draw_disc(&t, x + shift_px * v->cos_t, y + shift_px * v->sin_t, b->radius_m[j] * l->scale_px_per_m,
                            b->angle_rad[j] - slope);
        }
    return 0;
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
    const view_frame v = {cos(slope), sin(slope), -INFINITY, INFINITY, 0};
    const int fixed = p->render.view == SURGE_VIEW_FIXED;
    double X0 = INFINITY, X1 = -INFINITY, Y0 = INFINITY, Y1 = -INFINITY;
    for (int pass = 0; pass < 2 && !(X1 > X0); pass++) /* the fixed walls; every particle when there are none */
        for (int i = 0; i < s->count; i++) {
            const int fixed_wall = s->kind[i] == SURGE_KIND_WALL || s->kind[i] == SURGE_KIND_MOVING_WALL;
            if ((pass == 0 && !fixed_wall) || (fixed && (s->x_m[i] < p->render.view_x0_m ||
                                                         s->x_m[i] > p->render.view_x1_m)))
                continue;
            double X, Y;
            world_xy(&v, s->x_m[i], s->y_m[i], &X, &Y);
            X0 = fmin(X0, X), X1 = fmax(X1, X), Y0 = fmin(Y0, Y), Y1 = fmax(Y1, Y);
        }
    if (!p->render.true_slope) {
        /* along the bed, up to a little above the initial fluid block (layout_view's margin over the fluid) */
        Y1 = fmax(Y0, p->fluid.depth_m + 0.15 * (p->fluid.depth_m - Y0) + p->numerics.dp_m);
        if (p->render.view != SURGE_VIEW_WHOLE) {
            X0 = fixed ? p->render.view_x0_m : 0;
            X1 = fixed ? p->render.view_x1_m : p->render.view_width_m;
        } else if (p->domain.periodic_x) { /* the initial block with the periodic whole view's margins */
            X0 = 0;
            X1 = fmin(p->domain.length_m, 1.08 * (p->fluid.x1_m - p->fluid.x0_m) + 4 * p->numerics.dp_m);
        }
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
    view_frame v;
    return layout_view(c, s, p, snapshot_belt_mps(s), &v) == 0 ? &c->layout : NULL;
}

/* The GL discs, inside the plot area. Returns 0, or -1 when GL failed. */
static int draw_instances(surge_canvas *c, int n)
{
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
    return glGetError() == GL_NO_ERROR ? 0 : -1;
}

/* The label above the plot: the time, what drives the flow (the slope and the belt), and the discs with what their
 * spoke means and their solid fraction over the initial fluid block's area (docs/validation/debris_surge.md). */
static void draw_label(surge_canvas *c, const surge_snapshot *s, const surge_params *p)
{
    char label[200];
    int used = snprintf(label, sizeof label, "t = %.3f s", s->time_s);
    if (p->body.slope_deg != 0 && used > 0 && used < (int)sizeof label)
        used += snprintf(label + used, sizeof label - (size_t)used, "   slope %.3g deg", p->body.slope_deg);
    if (p->walls.bottom && p->walls.bottom_speed_mps != 0 && used > 0 && used < (int)sizeof label)
        used += snprintf(label + used, sizeof label - (size_t)used, "   belt %.3g m/s", p->walls.bottom_speed_mps);
    const double block_m2 = (p->fluid.x1_m - p->fluid.x0_m) * p->fluid.depth_m;
    if (s->boulders.count > 0 && block_m2 > 0 && used > 0 && used < (int)sizeof label) {
        double area = 0;
        for (int k = 0; k < s->boulders.count; k++)
            area += pi * s->boulders.radius_m[k] * s->boulders.radius_m[k];
        snprintf(label + used, sizeof label - (size_t)used, "   %d discs, phi %.2g (spoke: a disc's rotation)",
                 s->boulders.count, area / block_m2);
    }
    const int size = surge_text_size(c->text);
    surge_text_draw(c->text, c->pixels, c->width, c->height, c->layout.plot_x0, c->layout.plot_y0 - size / 2, label,
                    ink_rgb);
}

const uint8_t *surge_canvas_draw(surge_canvas *c, const surge_snapshot *s, const surge_params *p)
{
    const double belt_mps = snapshot_belt_mps(s);
    view_frame v;
    if (layout_view(c, s, p, belt_mps, &v) != 0)
        return NULL;
    const int n = fill_instances(c, s, p, &v, belt_mps);
    if (n < 0 || draw_instances(c, n) != 0 || draw_layers(c, s, p, &v, belt_mps) != 0)
        return NULL;
    const surge_canvas_layout *l = &c->layout;
    outline_rect(c, l->plot_x0, l->plot_y0, l->plot_x1, l->plot_y1);
    draw_colorbar(c, p);
    draw_length_scale(c);
    draw_drivers(c, p);
    draw_label(c, s, p);
    return c->pixels;
}

int surge_canvas_png(const surge_canvas *c, uint8_t **png, size_t *png_len, char *err, size_t err_len)
{
    return surge_png_encode_rgba(c->pixels, c->width, c->height, png, png_len, err, err_len);
}
