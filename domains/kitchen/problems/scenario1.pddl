; Scenario 1 (Sec. 5.5, Fig. 5.11): from its start the B21 carries one cup from table1 to table2: goto, grip,
; cross, goto, put. p1 is where it stands to grip cup1, d1 where it stands to put it down, w1 where it passes
; the door from room A (start, table1) to room B (table2).
(define (problem scenario1)
  (:domain kitchen)
  (:objects start p1 d1 w1 - spot
            table1 table2 - furniture
            cup1 - cup
            roomA roomB - room)
  (:init (robot start) (handempty) (in start roomA)
         (in p1 roomA) (in d1 roomB) (door w1 roomA roomB) (in w1 roomB) (unused w1)
         (table table1) (table table2)
         (serves p1 table1) (serves d1 table2)
         (on cup1 table1) (pickup p1 cup1) (dropoff d1 cup1))
  (:goal (on cup1 table2)))
