; An 'M': up the left stem (m1 -> m2), down to the middle (m3), up (m4), down the right stem (m5).
(define (problem letter-m)
  (:domain arm)
  (:objects m1 m2 m3 m4 m5 - waypoint)
  (:init (at m1)
         (next m1 m2) (next m2 m3) (next m3 m4) (next m4 m5)
         (rest m5))
  (:goal (and (reached m2) (reached m3) (reached m4) (reached m5)
              (at m5) (rest m5))))
