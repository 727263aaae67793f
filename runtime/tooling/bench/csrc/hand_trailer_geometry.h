/*
 * The shipped trailer robot's geometry (modeling/robots/trailer/trailer.toml), compiled in
 * as the generated code compiles it in: shared by the hand-written competitors
 * hand_trailer.c and hand_trailer_tdroc.c. L(x) is the including file's literal in its
 * working precision. Not used by the toolchain.
 */
#ifndef HAND_TRAILER_GEOMETRY_H
#define HAND_TRAILER_GEOMETRY_H

#define HB L(0.207) /* half the drive track */
#define A L(0.30)   /* drive axle to hitch */
#define LC L(0.60)  /* hitch to the cart's axle */
#define CB L(0.20)  /* half the cart's track */

#endif /* HAND_TRAILER_GEOMETRY_H */
