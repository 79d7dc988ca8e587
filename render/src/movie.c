/* Movies: RGBA frames streamed to the ffmpeg program (see surge/render.h). ffmpeg reads them from a socket
 * pair rather than a pipe so that a dead ffmpeg gives an error, not SIGPIPE. */
#define _GNU_SOURCE
#include "surge/render.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

struct surge_movie {
    pid_t pid;
    int fd; /* our end of the socket pair: ffmpeg's stdin */
    size_t frame_bytes;
    char path[4096];
};

/* Runs argv with stdin from in_fd (or /dev/null) and stdout/stderr to out_fd (or inherited); returns the pid.
 * The child gets its own process group, so that Ctrl-C in the terminal stops surge (which then finishes the
 * movie) and not ffmpeg halfway. */
static pid_t spawn(char *const argv[], int in_fd, int out_fd)
{
    posix_spawnattr_t attributes;
    posix_spawnattr_init(&attributes);
    posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);
    posix_spawnattr_setpgroup(&attributes, 0);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    if (in_fd >= 0)
        posix_spawn_file_actions_adddup2(&actions, in_fd, STDIN_FILENO);
    else
        posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
    if (out_fd >= 0)
        posix_spawn_file_actions_adddup2(&actions, out_fd, STDOUT_FILENO);
    pid_t pid;
    const int rc = posix_spawnp(&pid, argv[0], &actions, &attributes, argv, environ);
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attributes);
    return rc == 0 ? pid : -1;
}

/* Whether this ffmpeg has the libx264 encoder. */
static int ffmpeg_has_x264(void)
{
    int fds[2];
    if (pipe2(fds, O_CLOEXEC) != 0)
        return 0;
    char *argv[] = {"ffmpeg", "-hide_banner", "-encoders", NULL};
    const pid_t pid = spawn(argv, -1, fds[1]);
    close(fds[1]);
    char buf[65536];
    size_t len = 0;
    ssize_t n;
    while ((n = read(fds[0], buf + len, sizeof buf - 1 - len)) > 0)
        len += (size_t)n;
    buf[len] = '\0';
    close(fds[0]);
    if (pid > 0)
        waitpid(pid, NULL, 0);
    return strstr(buf, " libx264 ") != NULL;
}

surge_movie *surge_movie_open(const char *path, int width_px, int height_px, double fps, char *err, size_t err_len)
{
    /* can we write it? (without truncating a movie that is there, in case ffmpeg cannot start) */
    int created = 1, probe = open(path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (probe < 0 && errno == EEXIST) {
        created = 0;
        probe = open(path, O_WRONLY | O_CLOEXEC);
    }
    if (probe < 0) {
        snprintf(err, err_len, "cannot write the movie '%s': %s", path, strerror(errno));
        return NULL;
    }
    close(probe);
    const int x264 = ffmpeg_has_x264();
    int fds[2];
    if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0) {
        if (created)
            unlink(path);
        snprintf(err, err_len, "cannot start ffmpeg: %s", strerror(errno));
        return NULL;
    }
    char size[32], rate[32];
    snprintf(size, sizeof size, "%dx%d", width_px, height_px);
    snprintf(rate, sizeof rate, "%.6g", fps);
    char *argv[] = {"ffmpeg", "-hide_banner", "-loglevel", "error", "-y", "-f", "rawvideo", "-pixel_format", "rgba",
                    "-video_size", size, "-framerate", rate, "-i", "-",
                    "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", /* yuv420p needs even sizes */
                    "-c:v", x264 ? "libx264" : "mpeg4", x264 ? "-crf" : "-q:v", x264 ? "18" : "3",
                    "-pix_fmt", "yuv420p", "-movflags", "+faststart", (char *)path, NULL};
    const pid_t pid = spawn(argv, fds[1], -1);
    close(fds[1]);
    if (pid < 0) {
        close(fds[0]);
        if (created)
            unlink(path);
        snprintf(err, err_len, "cannot run ffmpeg to write '%s' (apt-get install ffmpeg; or use --frames and "
                               "assemble the movie later)", path);
        return NULL;
    }
    surge_movie *m = calloc(1, sizeof *m);
    if (!m) {
        close(fds[0]);
        kill(pid, SIGTERM);
        waitpid(pid, NULL, 0);
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    m->pid = pid;
    m->fd = fds[0];
    m->frame_bytes = (size_t)width_px * (size_t)height_px * 4;
    snprintf(m->path, sizeof m->path, "%s", path);
    return m;
}

int surge_movie_add(surge_movie *m, const uint8_t *rgba, char *err, size_t err_len)
{
    size_t sent = 0;
    while (sent < m->frame_bytes) {
        const ssize_t n = send(m->fd, rgba + sent, m->frame_bytes - sent, MSG_NOSIGNAL);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0) {
            snprintf(err, err_len, "ffmpeg stopped taking frames for '%s': %s", m->path, strerror(errno));
            return -1;
        }
        sent += (size_t)n;
    }
    return 0;
}

int surge_movie_close(surge_movie *m, char *err, size_t err_len)
{
    close(m->fd);
    int status = 0;
    while (waitpid(m->pid, &status, 0) < 0 && errno == EINTR)
        ;
    const int ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    if (!ok)
        snprintf(err, err_len, "ffmpeg failed writing '%s' (exit status %d)", m->path,
                 WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    free(m);
    return ok ? 0 : -1;
}
