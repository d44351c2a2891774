; An 'L': down the stem (l1 -> l2 -> l3) and along the foot (l4).
(define (problem letter-l)
  (:domain arm)
  (:objects l1 l2 l3 l4 - waypoint)
  (:init (at l1)
         (next l1 l2) (next l2 l3) (next l3 l4)
         (rest l4))
  (:goal (and (reached l2) (reached l3) (reached l4)
              (at l4) (rest l4))))
