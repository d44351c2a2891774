; Fig. 5.13(a): an 'F' in one stroke: up the stem (f1 -> f2 -> f3), along the top bar (f4), back to the
; stem (f5) and along the middle bar (f6, f7); the belief file places the way-points.
(define (problem letter-f)
  (:domain arm)
  (:objects f1 f2 f3 f4 f5 f6 f7 - waypoint)
  (:init (at f1)
         (next f1 f2) (next f2 f3) (next f3 f4) (next f4 f5) (next f5 f6) (next f6 f7)
         (rest f7))
  (:goal (and (reached f2) (reached f3) (reached f4) (reached f5) (reached f6) (reached f7)
              (at f7) (rest f7))))
