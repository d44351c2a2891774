; A generic stroke of 6 way-points (the random situations of `tailor evaluate arm` are of this shape):
; p1 -> ... -> p6, the pen resting at the end; the belief file is one example.
(define (problem stroke-6)
  (:domain arm)
  (:objects p1 p2 p3 p4 p5 p6 - waypoint)
  (:init (at p1)
         (next p1 p2) (next p2 p3) (next p3 p4) (next p4 p5) (next p5 p6)
         (rest p6))
  (:goal (and (reached p2) (reached p3) (reached p4) (reached p5) (reached p6)
              (at p6) (rest p6))))
