; A 'Z': along the top (z1 -> z2), down the diagonal through its middle (z3, z4), along the foot (z5).
(define (problem letter-z)
  (:domain arm)
  (:objects z1 z2 z3 z4 z5 - waypoint)
  (:init (at z1)
         (next z1 z2) (next z2 z3) (next z3 z4) (next z4 z5)
         (rest z5))
  (:goal (and (reached z2) (reached z3) (reached z4) (reached z5)
              (at z5) (rest z5))))
