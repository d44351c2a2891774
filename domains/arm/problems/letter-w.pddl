; A 'W': four strokes from the top left (w1) through the bottoms (w2, w4) and the middle (w3) to w5.
(define (problem letter-w)
  (:domain arm)
  (:objects w1 w2 w3 w4 w5 - waypoint)
  (:init (at w1)
         (next w1 w2) (next w2 w3) (next w3 w4) (next w4 w5)
         (rest w5))
  (:goal (and (reached w2) (reached w3) (reached w4) (reached w5)
              (at w5) (rest w5))))
