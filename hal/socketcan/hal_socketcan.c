/// hal_socketcan: CAN_RAW frame I/O (see hal_socketcan.h). _DEFAULT_SOURCE (struct ifreq, SIOCGIFINDEX)
/// comes from CMakeLists.txt.
#include "hal_socketcan.h"

#include <errno.h>
#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <time.h>
#include <unistd.h>

#ifndef SO_RXQ_OVFL
#define SO_RXQ_OVFL 40
#endif

uint64_t hal_socketcan_now_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (uint64_t)ts.tv_sec * 1000000U + (uint64_t)ts.tv_nsec / 1000U;
}

/// Interface flags; -1 if it does not exist.
static int if_flags(int fd, const char *name)
{
    struct ifreq ifr;
    memset(&ifr, 0, sizeof ifr);
    (void)snprintf(ifr.ifr_name, sizeof ifr.ifr_name, "%s", name);
    if (ioctl(fd, SIOCGIFFLAGS, &ifr) != 0) {
        return -1;
    }
    return ifr.ifr_flags;
}

static int open_socket(hal_socketcan_t *s)
{
    const int fd = socket(PF_CAN, SOCK_RAW, CAN_RAW);
    if (fd < 0) {
        if (errno == EAFNOSUPPORT) {
            (void)snprintf(s->err, sizeof s->err,
                           "this kernel has no SocketCAN (socket(AF_CAN): %s); load the can and can_raw "
                           "modules",
                           strerror(errno));
        } else {
            (void)snprintf(s->err, sizeof s->err, "socket(AF_CAN): %s", strerror(errno));
        }
        return -1;
    }
    const unsigned idx = if_nametoindex(s->ifname);
    if (idx == 0U) {
        (void)snprintf(s->err, sizeof s->err, "no interface '%s' (%s)", s->ifname, strerror(errno));
        close(fd);
        return -1;
    }
    struct can_filter flt[HAL_SC_MAX_FILTERS];
    for (size_t i = 0; i < s->n_ids; ++i) {
        flt[i].can_id = s->ids[i];
        flt[i].can_mask = CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG; /* standard data frames */
    }
    const can_err_mask_t errmask = CAN_ERR_MASK;
    const int one = 1;
    if ((s->n_ids > 0U &&
         setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, flt, (socklen_t)(s->n_ids * sizeof flt[0])) != 0) ||
        setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errmask, sizeof errmask) != 0 ||
        setsockopt(fd, SOL_SOCKET, SO_TIMESTAMP, &one, sizeof one) != 0) {
        (void)snprintf(s->err, sizeof s->err, "%s: setsockopt: %s", s->ifname, strerror(errno));
        close(fd);
        return -1;
    }
    (void)setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one); /* optional: drop counter */
    struct sockaddr_can addr;
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = (int)idx;
    if (bind(fd, (struct sockaddr *)&addr, sizeof addr) != 0) {
        (void)snprintf(s->err, sizeof s->err, "%s: bind: %s (is it a CAN interface?)", s->ifname, strerror(errno));
        close(fd);
        return -1;
    }
    const int fl = fcntl(fd, F_GETFL, 0);
    if (fl < 0 || fcntl(fd, F_SETFL, fl | O_NONBLOCK) != 0) {
        (void)snprintf(s->err, sizeof s->err, "%s: fcntl: %s", s->ifname, strerror(errno));
        close(fd);
        return -1;
    }
    s->fd = fd;
    s->ifindex = (int)idx;
    const int flags = if_flags(fd, s->ifname);
    s->up = flags >= 0 && (flags & IFF_UP) != 0;
    return 0;
}

int hal_socketcan_open(hal_socketcan_t *s, const char *ifname, const uint32_t *ids, size_t n_ids)
{
    memset(s, 0, sizeof *s);
    s->fd = -1;
    if (strlen(ifname) == 0U || strlen(ifname) >= sizeof s->ifname) {
        (void)snprintf(s->err, sizeof s->err, "interface name must be 1 to 15 characters");
        return -1;
    }
    if (n_ids > HAL_SC_MAX_FILTERS) {
        (void)snprintf(s->err, sizeof s->err, "at most %u filter identifiers", HAL_SC_MAX_FILTERS);
        return -1;
    }
    (void)snprintf(s->ifname, sizeof s->ifname, "%s", ifname);
    memcpy(s->ids, ids, n_ids * sizeof ids[0]);
    s->n_ids = n_ids;
    if (open_socket(s) != 0) {
        return -1;
    }
    if (!s->up) {
        (void)snprintf(s->err, sizeof s->err, "interface '%s' is down (ip link set %s up)", ifname, ifname);
        hal_socketcan_close(s);
        return -1;
    }
    return 0;
}

void hal_socketcan_close(hal_socketcan_t *s)
{
    if (s->fd >= 0) {
        close(s->fd);
    }
    s->fd = -1;
}

int hal_socketcan_wait(hal_socketcan_t *s, int timeout_ms)
{
    if (s->fd < 0) {
        if (timeout_ms > 0) {
            (void)poll(NULL, 0, timeout_ms);
        }
        return 0;
    }
    struct pollfd p = {.fd = s->fd, .events = POLLIN, .revents = 0};
    const int r = poll(&p, 1, timeout_ms);
    if (r < 0) {
        if (errno == EINTR) {
            return 0;
        }
        (void)snprintf(s->err, sizeof s->err, "%s: poll: %s", s->ifname, strerror(errno));
        return -1;
    }
    return r > 0 ? 1 : 0;
}

hal_sc_status_t hal_socketcan_recv(hal_socketcan_t *s, odo_can_frame_t *frame, uint64_t *t_us)
{
    if (s->fd < 0) {
        return HAL_SC_DOWN;
    }
    struct can_frame cf;
    char ctrl[CMSG_SPACE(sizeof(struct timeval)) + CMSG_SPACE(sizeof(uint32_t))];
    struct iovec iov = {.iov_base = &cf, .iov_len = sizeof cf};
    struct msghdr msg;
    memset(&msg, 0, sizeof msg);
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = ctrl;
    msg.msg_controllen = sizeof ctrl;
    const ssize_t n = recvmsg(s->fd, &msg, MSG_DONTWAIT);
    if (n < 0) {
        if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) {
            return HAL_SC_NONE;
        }
        if (errno == ENETDOWN || errno == ENODEV || errno == ENXIO) {
            s->up = false;
            s->stats.down_events++;
            return HAL_SC_DOWN;
        }
        (void)snprintf(s->err, sizeof s->err, "%s: recvmsg: %s", s->ifname, strerror(errno));
        return HAL_SC_ERROR;
    }
    if ((size_t)n < sizeof cf) {
        return HAL_SC_NONE; /* not a classic frame (cannot happen without CAN_RAW_FD_FRAMES) */
    }
    uint64_t ts = 0U;
    for (struct cmsghdr *c = CMSG_FIRSTHDR(&msg); c != NULL; c = CMSG_NXTHDR(&msg, c)) {
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_TIMESTAMP) {
            struct timeval tv;
            memcpy(&tv, CMSG_DATA(c), sizeof tv);
            ts = (uint64_t)tv.tv_sec * 1000000U + (uint64_t)tv.tv_usec;
        } else if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
            uint32_t drops;
            memcpy(&drops, CMSG_DATA(c), sizeof drops);
            if (drops != s->kernel_drops) {
                s->stats.rx_dropped += (uint32_t)(drops - s->kernel_drops);
                s->kernel_drops = drops;
            }
        }
    }
    *t_us = ts != 0U ? ts : hal_socketcan_now_us();
    memset(frame, 0, sizeof *frame);
    frame->dlc = cf.can_dlc > 8U ? 8U : cf.can_dlc;
    if ((cf.can_id & CAN_ERR_FLAG) != 0U) {
        frame->id = cf.can_id & CAN_ERR_MASK;
        frame->flags = ODO_CAN_FLAG_ERR;
        s->stats.error_frames++;
        s->stats.bus_off += (cf.can_id & CAN_ERR_BUSOFF) != 0U;
    } else if ((cf.can_id & CAN_EFF_FLAG) != 0U) {
        frame->id = cf.can_id & CAN_EFF_MASK;
        frame->flags = ODO_CAN_FLAG_EXT;
    } else {
        frame->id = cf.can_id & CAN_SFF_MASK;
    }
    if ((cf.can_id & CAN_RTR_FLAG) != 0U) {
        frame->flags |= ODO_CAN_FLAG_RTR;
    } else {
        memcpy(frame->data, cf.data, frame->dlc);
    }
    s->stats.rx_frames++;
    s->up = true;
    return HAL_SC_FRAME;
}

bool hal_socketcan_send(hal_socketcan_t *s, const odo_can_frame_t *frame)
{
    if (s->fd < 0) {
        s->stats.tx_dropped++;
        return false;
    }
    struct can_frame cf;
    memset(&cf, 0, sizeof cf);
    cf.can_id = frame->id;
    if ((frame->flags & ODO_CAN_FLAG_EXT) != 0U) {
        cf.can_id = (frame->id & CAN_EFF_MASK) | CAN_EFF_FLAG;
    }
    if ((frame->flags & ODO_CAN_FLAG_RTR) != 0U) {
        cf.can_id |= CAN_RTR_FLAG;
    }
    cf.can_dlc = frame->dlc > 8U ? 8U : frame->dlc;
    memcpy(cf.data, frame->data, cf.can_dlc);
    for (int attempt = 0; attempt < 2; ++attempt) {
        const ssize_t n = write(s->fd, &cf, sizeof cf);
        if (n == (ssize_t)sizeof cf) {
            s->stats.tx_frames++;
            return true;
        }
        if (n < 0 && (errno == ENOBUFS || errno == EAGAIN || errno == EWOULDBLOCK) && attempt == 0) {
            /* Queue full: give the driver a moment, once. The tick is never held longer. */
            s->stats.tx_retries++;
            struct pollfd p = {.fd = s->fd, .events = POLLOUT, .revents = 0};
            (void)poll(&p, 1, HAL_SC_SEND_WAIT_MS);
            continue;
        }
        if (n < 0 && (errno == ENETDOWN || errno == ENODEV || errno == ENXIO)) {
            s->up = false;
            s->stats.down_events++;
        }
        break;
    }
    s->stats.tx_dropped++;
    return false;
}

bool hal_socketcan_check_up(hal_socketcan_t *s)
{
    const unsigned idx = if_nametoindex(s->ifname);
    if (idx == 0U) {
        s->up = false;
        return false; /* deleted; it may come back */
    }
    if (s->fd < 0 || (int)idx != s->ifindex) {
        hal_socketcan_close(s);
        if (open_socket(s) != 0) {
            return false;
        }
        s->stats.reopens++;
    }
    const int flags = if_flags(s->fd, s->ifname);
    s->up = flags >= 0 && (flags & IFF_UP) != 0;
    return s->up;
}
