/* The live links of a run: opening them from the options, serving them between steps, and their closing report. */
#include "live_links.h"

#include <stdio.h>
#include <string.h>

#include <zmq.h>

#include "surge/platform.h"
#include "surge/run.h"

/* Renderer thread: rendered frames also go out on the stream. */
static void publish_rendered_frame(const uint8_t *png, size_t png_len, int64_t step, double time_s, void *user)
{
    surge_publisher_post_png(user, png, png_len, step, time_s);
}

int at_step_boundary(surge_sim *sim, void *user)
{
    live_links *l = user;
    int requests = SURGE_CONTINUE;
    if (l->replay) {
        const int replayed = surge_replay_apply(l->replay, sim, l->journal, l->replay_error, sizeof l->replay_error);
        if (replayed < 0)
            return SURGE_REQUEST_STOP;
        requests |= replayed;
    }
    if (l->control)
        requests |= surge_control_service(l->control, sim, l->stop_requested);
    if (l->publisher)
        surge_publisher_offer(l->publisher, sim);
    if (l->renderer)
        surge_renderer_offer(l->renderer, sim);
    return requests;
}

/* The renderer of --frames and --movie, its frames also published when there is a publisher. */
static int start_renderer(const cli *c, const surge_sim *sim, live_links *l, char *err, size_t err_len)
{
    surge_renderer_def def = {.frames_dir = c->frames_dir, .movie_path = c->movie_path, .font_path = c->font_path,
                              .continue_frames = c->restart_path != NULL, .resume_time_s = surge_sim_time(sim)};
    if (l->publisher) {
        def.on_frame = publish_rendered_frame;
        def.user = l->publisher;
    }
    surge_params render_params = *surge_sim_params(sim);
    if (fit_frame_height(&render_params, sim, NULL, err, err_len) != 0 ||
        !(l->renderer = surge_renderer_start(&def, &render_params, err, err_len)))
        return -1;
    l->movie_path = c->movie_path;
    return 0;
}

int open_live_links(const cli *c, const char *outdir, const surge_sim *sim, volatile sig_atomic_t *stop_requested,
                    live_links *l)
{
    char err[1024], path[4200];
    memset(l, 0, sizeof *l);
    l->stop_requested = stop_requested;
    if (c->replay_path && !(l->replay = surge_replay_load(c->replay_path, err, sizeof err)))
        goto fail;
    if (c->control[0] || c->replay_path) {
        snprintf(path, sizeof path, "%s/control.jsonl", outdir);
        const long long resume_step = c->restart_path ? (long long)surge_sim_step_count(sim) : -1;
        if (!(l->journal = surge_journal_open(path, resume_step, err, sizeof err)))
            goto fail;
    }
    if (c->publish[0] || c->control[0])
        l->zmq_context = zmq_ctx_new();
    /* the outputs must never run short of file descriptors: the run takes all the files it may open, and its
     * sockets' peers are capped to an eighth of them each (a peer being closed holds its descriptor a moment
     * longer, so up to twice that), so that at least half stay for everything else */
    const long files = surge_raise_file_limit();
    const int peer_cap = files < 0 ? 1000 : (int)(files / 8 < 4 ? 4 : files / 8 > 1000 ? 1000 : files / 8);
    if (c->curve_key_path) {
        if (!(l->curve = surge_curve_server_start(l->zmq_context, c->curve_key_path, c->curve_clients_path, err,
                                                  sizeof err)))
            goto fail;
        fprintf(stderr, "surge: CURVE security: %d allowed client key%s (%s)\n", surge_curve_allowed_count(l->curve),
                surge_curve_allowed_count(l->curve) == 1 ? "" : "s", c->curve_clients_path);
    } else if (c->publish[0] && !(l->numbering = surge_curve_numbering_start(l->zmq_context, err, sizeof err))) {
        goto fail; /* the publisher tells its subscribers apart by the number the handler gives each connection */
    }
    if (c->control[0]) {
        surge_control_def def = surge_default_control_def();
        def.endpoint = c->control;
        def.curve = l->curve;
        def.start_paused = c->paused;
        def.max_peers = def.max_peers < peer_cap ? def.max_peers : peer_cap;
        if (!(l->control = surge_control_start(l->zmq_context, &def, l->journal, err, sizeof err)))
            goto fail;
    }
    if (c->publish[0]) {
        surge_publisher_def def = c->publisher;
        def.endpoint = c->publish;
        def.curve = l->curve ? l->curve : l->numbering;
        def.max_peers = def.max_peers < peer_cap ? def.max_peers : peer_cap;
        if (!(l->publisher = surge_publisher_start(l->zmq_context, &def, err, sizeof err)))
            goto fail;
    }
    if ((c->frames_dir || c->movie_path) && start_renderer(c, sim, l, err, sizeof err) != 0)
        goto fail;
    return 0;
fail:
    fprintf(stderr, "surge: %s\n", err);
    return -1;
}

/* Waits for the renderer's last frames and says what it drew; -1 when it failed. */
static int finish_renderer(const live_links *l)
{
    surge_render_report r;
    char err[1024];
    const int rc = surge_renderer_finish(l->renderer, &r, err, sizeof err);
    if (rc != 0)
        fprintf(stderr, "surge: rendering failed: %s\n", err);
    fprintf(stderr, "surge: rendered %llu of %llu frames due (%llu skipped while the renderer was busy), "
                    "%.1f ms per frame drawing, %.1f ms encoding\n",
            (unsigned long long)r.frames_drawn, (unsigned long long)r.frames_due,
            (unsigned long long)(r.frames_due - r.frames_drawn), r.frames_drawn ? 1e3 * r.draw_s / r.frames_drawn : 0,
            r.frames_drawn ? 1e3 * r.encode_s / r.frames_drawn : 0);
    if (l->movie_path && r.movie_frames_before_restart > 0)
        fprintf(stderr, "surge: movie %s: %llu frames (%llu of them drawn before the restart)\n", l->movie_path,
                (unsigned long long)r.movie_frames, (unsigned long long)r.movie_frames_before_restart);
    else if (l->movie_path)
        fprintf(stderr, "surge: movie %s: %llu frames\n", l->movie_path, (unsigned long long)r.movie_frames);
    return rc;
}

int close_live_links(live_links *l, const surge_sim *sim)
{
    const int rc = l->renderer ? finish_renderer(l) : 0;
    if (l->publisher) {
        surge_publisher_report r;
        surge_publisher_finish(l->publisher, sim, &r);
        fprintf(stderr, "surge: published %llu states (%llu superseded by newer ones before sending), %llu messages, "
                        "%.1f MB\n", (unsigned long long)r.frames_posted, (unsigned long long)r.frames_superseded,
                (unsigned long long)r.messages_sent, 1e-6 * (double)r.bytes_sent);
        if (r.peers_over_limit > 0)
            fprintf(stderr, "surge: closed %ld subscriber connection%s over the limit of peers at once\n",
                    r.peers_over_limit, r.peers_over_limit == 1 ? "" : "s");
    }
    long over_limit = 0, idle = 0;
    surge_control_peer_counts(l->control, &over_limit, &idle);
    if (over_limit + idle > 0)
        fprintf(stderr, "surge: closed %ld control connection%s over the limit of peers at once and %ld idle\n",
                over_limit, over_limit == 1 ? "" : "s", idle);
    surge_control_end end;
    surge_control_close(l->control, &end);
    if (end.refused > 0)
        fprintf(stderr, "surge: control: refused %ld request%s that waited or came after the run ended\n", end.refused,
                end.refused == 1 ? "" : "s");
    if (end.undelivered > 0)
        fprintf(stderr, "surge: control: %ld repl%s not delivered to %d client%s that %s\n", end.undelivered,
                end.undelivered == 1 ? "y" : "ies", end.clients_left, end.clients_left == 1 ? "" : "s",
                end.stalled ? "read nothing for 1 s" : "had not read them 5 s after the end");
    else if (end.time_limit)
        fprintf(stderr, "surge: control: closed 5 s after the run ended, requests still coming\n");
    surge_replay_free(l->replay);
    surge_journal_close(l->journal);
    if (l->curve && surge_curve_refused_count(l->curve) > 0)
        fprintf(stderr, "surge: refused %ld connection%s whose client key was not allowed\n",
                surge_curve_refused_count(l->curve), surge_curve_refused_count(l->curve) == 1 ? "" : "s");
    surge_curve_server_stop(l->curve);
    surge_curve_server_stop(l->numbering);
    if (l->zmq_context)
        zmq_ctx_term(l->zmq_context);
    return rc;
}
