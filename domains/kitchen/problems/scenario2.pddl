; Scenario 2 (Sec. 5.5): as Scenario 1, but two cups are delivered from table1 to table2, one at a time (eleven
; actions: goto, grip, cross, goto, put for each cup, and a crossing back between them). p<i> / d<i>: where the
; B21 stands to grip / put down cup<i>; w1, w3 pass the door from room A to room B, w2 back.
(define (problem scenario2)
  (:domain kitchen)
  (:objects start p1 d1 p2 d2 w1 w2 w3 - spot
            table1 table2 - furniture
            cup1 cup2 - cup
            roomA roomB - room)
  (:init (robot start) (handempty) (in start roomA)
         (in p1 roomA) (in p2 roomA) (in d1 roomB) (in d2 roomB)
         (door w1 roomA roomB) (door w2 roomB roomA) (door w3 roomA roomB) (in w1 roomB) (in w2 roomA) (in w3 roomB)
         (unused w1) (unused w2) (unused w3)
         (table table1) (table table2)
         (serves p1 table1) (serves d1 table2) (serves p2 table1) (serves d2 table2)
         (on cup1 table1) (pickup p1 cup1) (dropoff d1 cup1)
         (on cup2 table1) (pickup p2 cup2) (dropoff d2 cup2))
  (:goal (and (on cup1 table2) (on cup2 table2))))
