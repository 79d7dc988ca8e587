/* The explicit scheme's private header: what its files share. */
#ifndef SURGE_EXPLICIT_H
#define SURGE_EXPLICIT_H

#include <stdio.h>

#include "sim_internal.h"

/* explicit_discs.c: the discs' predictor (saves the step start, moves to the half step) and corrector (the full step
 * from the start, with contacts; -1 when the contact solver runs out of memory) */
void explicit_discs_predict(surge_sim *sim, double half_dt_s);
int explicit_discs_correct(surge_sim *sim, double dt_s);
/* after the fluid's update: the discs take the reaction of the contact rule's velocity changes on their faces */
void explicit_discs_take_contact_reactions(surge_sim *sim, double dt_s);
/* explicit_report.c */
void explicit_check_report(const surge_sim *sim, FILE *out, int verbose, double list_entries, double bytes);

#endif
