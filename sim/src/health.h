/* The health monitor: a blow-up found, named and reported (health.c). */
#ifndef SURGE_HEALTH_H
#define SURGE_HEALTH_H

typedef struct surge_sim surge_sim;

/* -1 with sim->health set when a fluid particle fails a check */
int health_check(surge_sim *sim);

#endif
