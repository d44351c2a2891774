; Ch. 6 (Fig. 6.6, Table 6.1): the robot at pos1 approaches the ball at pos2, arriving with the heading and
; speed the belief state gives for pos2 (final), without bumping the ball first.
(define (problem approach)
  (:domain soccer)
  (:objects pos1 pos2 - pos)
  (:init (robot pos1) (ball pos2) (final pos2))
  (:goal (and (atball pos2) (final pos2))))
