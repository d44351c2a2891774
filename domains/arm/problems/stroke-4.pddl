; A generic stroke of 4 way-points (the random situations of `tailor evaluate arm` are of this shape):
; p1 -> ... -> p4, the pen resting at the end; the belief file is one example.
(define (problem stroke-4)
  (:domain arm)
  (:objects p1 p2 p3 p4 - waypoint)
  (:init (at p1)
         (next p1 p2) (next p2 p3) (next p3 p4)
         (rest p4))
  (:goal (and (reached p2) (reached p3) (reached p4)
              (at p4) (rest p4))))
