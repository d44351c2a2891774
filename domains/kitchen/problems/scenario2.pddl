; Scenario 2 (Sec. 5.5): as Scenario 1, but two cups are delivered from table1 to table2, one at a time (eight
; actions: goto, grip, goto, put for each cup). p<i> / d<i>: where the B21 stands to grip / put down cup<i>.
(define (problem scenario2)
  (:domain kitchen)
  (:objects start p1 d1 p2 d2 - spot
            table1 table2 - furniture
            cup1 cup2 - cup)
  (:init (robot start) (handempty)
         (table table1) (table table2)
         (serves p1 table1) (serves d1 table2) (serves p2 table1) (serves d2 table2)
         (on cup1 table1) (pickup p1 cup1) (dropoff d1 cup1)
         (on cup2 table1) (pickup p2 cup2) (dropoff d2 cup2))
  (:goal (and (on cup1 table2) (on cup2 table2))))
