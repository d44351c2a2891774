; An 'N': up the left stem (n1 -> n2), down the diagonal (n3), up the right stem (n4).
(define (problem letter-n)
  (:domain arm)
  (:objects n1 n2 n3 n4 - waypoint)
  (:init (at n1)
         (next n1 n2) (next n2 n3) (next n3 n4)
         (rest n4))
  (:goal (and (reached n2) (reached n3) (reached n4)
              (at n4) (rest n4))))
