/* Mathematical constants shared by every layer (firmware, HAL, tests, benches):
 * the one definition of each. Header-only, includes nothing. */
#ifndef LS_MATH_H
#define LS_MATH_H

/* pi to double precision (C11 has no standard M_PI). */
#define LS_PI 3.14159265358979323846

#endif /* LS_MATH_H */
